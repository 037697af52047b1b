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

"$ROOT/scripts/setup.sh"
if [ "$RVIZ" = true ] && ! command -v rviz >/dev/null; then
  echo "[demo] installing rviz" >&2
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends rviz >/dev/null
fi
export PYENV_VERSION=system ROS_HOSTNAME=localhost
set +u
# shellcheck disable=SC1091
source "$BUILD_DIR/devel/setup.bash"
set -u

DEMO="$ROOT/.demo"
BAG="$DEMO/room_${FRAMES}.bag"
mkdir -p "$DEMO" "$ROOT/demo_output"
if [ ! -f "$BAG" ]; then
  echo "[demo] generating the simulated room ($FRAMES frames, 640x480, SGBM) -> $BAG"
  "$BUILD_DIR/devel/lib/stereo_fusion/stereo_fusion_simulate" --preset room --trajectory walkthrough \
    --frames "$FRAMES" --disparity sgbm --seed 1 --out "$DEMO/room_${FRAMES}" --bag "$BAG.part"
  mv "$BAG.part" "$BAG"
fi

PORT="$(/usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("", 0)); print(s.getsockname()[1])')"
export ROS_MASTER_URI="http://localhost:$PORT"
PIDS=()
cleanup() {
  for pid in "${PIDS[@]}"; do kill -INT "$pid" 2>/dev/null || true; done
  sleep 1
  for pid in "${PIDS[@]}"; do kill -KILL "$pid" 2>/dev/null || true; done
}
trap cleanup EXIT
echo "[demo] ROS master on port $PORT"
roscore -p "$PORT" >"$DEMO/roscore.log" 2>&1 &
PIDS+=($!)
/usr/bin/python3 - <<PY
import time, rosgraph
for _ in range(100):
    if rosgraph.is_master_online():
        break
    time.sleep(0.1)
else:
    raise SystemExit("[demo] the ROS master did not come up, see $DEMO/roscore.log")
PY

echo "[demo] replaying $BAG through stereo_fusion (log: $DEMO/launch.log)"
roslaunch stereo_fusion replay.launch bag:="$BAG" rate:="$RATE" rviz:="$RVIZ" player_required:=false \
  >"$DEMO/launch.log" 2>&1 &
PIDS+=($!)
/usr/bin/python3 "$ROOT/tools/demo/demo_monitor.py" --frames "$FRAMES"
rosservice call /stereo_fusion/save_mesh "path: '$ROOT/demo_output/mesh.ply'"
if [ "$RVIZ" = true ]; then
  echo "[demo] rviz is open; press Enter to stop"
  read -r _
fi
echo "[demo] mesh saved to demo_output/mesh.ply"
