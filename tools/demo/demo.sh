#!/usr/bin/env bash
# The demo on a built or installed stereo_fusion (the package's ROS environment in place: the
# Debian package needs none, an install space its setup.bash, the build scripts/env.sh): generates
# the simulated room bag on first use, starts a ROS master on a free port, replays the bag through
# the nodelet (launch/replay.launch), prints progress and the per-stage timing table, saves the
# mesh as OUTPUT/mesh.ply and stops everything it started. scripts/demo.sh runs it on the build.
#   rosrun stereo_fusion demo.sh [--rviz] [--frames N] [--rate R] [--work-dir DIR] [--output-dir DIR]
# --work-dir keeps the bag and the logs (default ~/.cache/stereo_fusion/demo), --output-dir the
# mesh (default ./demo_output).
set -euo pipefail
FRAMES=100
RATE=1.0
RVIZ=false
WORK="${XDG_CACHE_HOME:-$HOME/.cache}/stereo_fusion/demo"
OUTPUT="$PWD/demo_output"
while [ $# -gt 0 ]; do
  case "$1" in
    --rviz) RVIZ=true; shift ;;
    --frames) FRAMES="$2"; shift 2 ;;
    --rate) RATE="$2"; shift 2 ;;
    --work-dir) WORK="$2"; shift 2 ;;
    --output-dir) OUTPUT="$2"; shift 2 ;;
    -h|--help) sed -n '2,9p' "$0"; exit 0 ;;
    *) echo "demo.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
export PYENV_VERSION=system  # the ROS tools run on Debian's Python (ros-on-debian.md #1)
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
# The package's executables: beside this script once installed, else where catkin puts them
# (the build's devel/lib/stereo_fusion).
BIN="$HERE"
if [ ! -x "$BIN/stereo_fusion_simulate" ]; then
  BIN="$(catkin_find --first-only --libexec stereo_fusion 2>/dev/null || true)"
  if [ -z "$BIN" ] || [ ! -x "$BIN/stereo_fusion_simulate" ]; then
    echo "demo.sh: stereo_fusion_simulate not found: source the package's setup.bash (scripts/env.sh for the build)" >&2
    exit 1
  fi
fi
# shellcheck source=tools/demo/demo_session.sh
source "$HERE/demo_session.sh"
demo_bag "$BIN/stereo_fusion_simulate" "$WORK" "$FRAMES" demo
mkdir -p "$OUTPUT"
OUTPUT="$(cd "$OUTPUT" && pwd)"

PIDS=()
trap stop_pids EXIT
start_master demo "$WORK/roscore.log"

echo "[demo] replaying $BAG through stereo_fusion (log: $WORK/launch.log)"
roslaunch stereo_fusion replay.launch bag:="$BAG" rate:="$RATE" rviz:="$RVIZ" player_required:=false \
  >"$WORK/launch.log" 2>&1 &
PIDS+=($!)
if ! /usr/bin/python3 "$BIN/demo_monitor.py" --frames "$FRAMES" --launch-pid "$!"; then
  echo "[demo] the launch failed; the end of $WORK/launch.log:" >&2
  tail -n 15 "$WORK/launch.log" >&2
  exit 1
fi
# rosservice prints the raw reply ("success: True / message: ..."): keep it for the log, say it once.
reply=$(rosservice call /stereo_fusion/save_mesh "path: '$OUTPUT/mesh.ply'" 2>&1) || true
echo "$reply" >>"$WORK/launch.log"
if ! grep -q "success: True" <<<"$reply"; then
  echo "[demo] saving the mesh failed: $reply" >&2
  exit 1
fi
message=$(sed -n 's/^message: //p' <<<"$reply" | sed 's/^"//; s/"$//')
echo "[demo] ${message:-mesh saved to $OUTPUT/mesh.ply}"
if [ "$RVIZ" = true ]; then
  echo "[demo] rviz is open; press Enter to stop"
  read -r _
fi
