#!/usr/bin/env bash
# The main job on the built-in default sequence: installs what is missing, builds, generates
# the simulated room bag on first use, starts a ROS master on a free port, replays the bag
# through the nodelet (launch/replay.launch), prints progress and the per-stage timing table,
# saves demo_output/mesh.ply and stops everything it started.
#   scripts/demo.sh [--rviz] [--frames N] [--rate R]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/.build}"
FRAMES=100
RATE=1.0
RVIZ=false
while [ $# -gt 0 ]; do
  case "$1" in
    --rviz) RVIZ=true; shift ;;
    --frames) FRAMES="$2"; shift 2 ;;
    --rate) RATE="$2"; shift 2 ;;
    -h|--help) sed -n '2,7p' "$0"; exit 0 ;;
    *) echo "demo.sh: unknown option $1" >&2; exit 2 ;;
  esac
done

"$ROOT/scripts/setup.sh" --targets "stereo_fusion_nodelet stereo_fusion_simulate stereo_fusion_generate_messages"
if [ "$RVIZ" = true ] && ! command -v rviz >/dev/null; then
  echo "[demo] installing rviz" >&2
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends rviz >/dev/null
fi
# shellcheck source=scripts/lib/ros_session.sh
source "$ROOT/scripts/lib/ros_session.sh"
ros_env
ensure_demo_bag "$FRAMES" demo
mkdir -p "$ROOT/demo_output"

PIDS=()
trap stop_pids EXIT
start_master demo "$DEMO/roscore.log"

echo "[demo] replaying $BAG through stereo_fusion (log: $DEMO/launch.log)"
roslaunch stereo_fusion replay.launch bag:="$BAG" rate:="$RATE" rviz:="$RVIZ" player_required:=false \
  >"$DEMO/launch.log" 2>&1 &
PIDS+=($!)
if ! /usr/bin/python3 "$ROOT/tools/demo/demo_monitor.py" --frames "$FRAMES" --launch-pid "$!"; then
  echo "[demo] the launch failed; the end of $DEMO/launch.log:" >&2
  tail -n 15 "$DEMO/launch.log" >&2
  exit 1
fi
# rosservice prints the raw reply ("success: True / message: ..."): keep it for the log, say it once.
reply=$(rosservice call /stereo_fusion/save_mesh "path: '$ROOT/demo_output/mesh.ply'" 2>&1) || true
echo "$reply" >>"$DEMO/launch.log"
if ! grep -q "success: True" <<<"$reply"; then
  echo "[demo] saving the mesh failed: $reply" >&2
  exit 1
fi
message=$(sed -n 's/^message: //p' <<<"$reply" | sed 's/^"//; s/"$//')
echo "[demo] ${message:-mesh saved} (demo_output/mesh.ply)"
if [ "$RVIZ" = true ]; then
  echo "[demo] rviz is open; press Enter to stop"
  read -r _
fi
