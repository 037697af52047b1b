#!/usr/bin/env bash
# rviz screenshots for the README, made headless: installs rviz, Xvfb and ImageMagick if missing
# (scripts/setup.sh --screenshots), replays the demo bag (the simulated room) through
# stereo_fusion with rviz on a virtual X display (software OpenGL, Mesa llvmpipe) and captures
# the screen:
#   doc/images/rviz_mapping.png   mid-run: mesh, camera path, current frustum
#   doc/images/rviz_final.png     after the last frame
#   doc/images/rviz_blocks.png    the same with the block bounds (debug) shown
#   scripts/screenshots.sh [--frames N]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/.build}"
FRAMES=100
while [ $# -gt 0 ]; do
  case "$1" in
    --frames) FRAMES="$2"; shift 2 ;;
    --inside-xvfb) INSIDE_XVFB=1; shift ;;
    -h|--help) sed -n '2,9p' "$0"; exit 0 ;;
    *) echo "screenshots.sh: unknown option $1" >&2; exit 2 ;;
  esac
done

if [ -z "${INSIDE_XVFB:-}" ]; then
  "$ROOT/scripts/setup.sh" --screenshots
  # One virtual screen for everything below; rviz renders with Mesa's software OpenGL.
  export LIBGL_ALWAYS_SOFTWARE=1
  exec xvfb-run -a -s "-screen 0 1280x800x24" "$0" --frames "$FRAMES" --inside-xvfb
fi

export PYENV_VERSION=system ROS_HOSTNAME=localhost
set +u
# shellcheck disable=SC1091
source "$BUILD_DIR/devel/setup.bash"
set -u
DEMO="$ROOT/.demo"
BAG="$DEMO/room_${FRAMES}.bag"
OUT="$ROOT/doc/images"
mkdir -p "$DEMO" "$OUT"
if [ ! -f "$BAG" ]; then
  echo "[screenshots] generating the simulated room ($FRAMES frames) -> $BAG"
  "$BUILD_DIR/devel/lib/stereo_fusion/stereo_fusion_simulate" --preset room --trajectory walkthrough \
    --frames "$FRAMES" --disparity sgbm --seed 1 --out "$DEMO/room_${FRAMES}" --bag "$BAG.part"
  mv "$BAG.part" "$BAG"
fi

PIDS=()
cleanup() {
  for pid in "${PIDS[@]}"; do kill -INT "$pid" 2>/dev/null || true; done
  sleep 1
  for pid in "${PIDS[@]}"; do kill -KILL "$pid" 2>/dev/null || true; wait "$pid" 2>/dev/null || true; done
}
trap cleanup EXIT
PORT="$(/usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("", 0)); print(s.getsockname()[1])')"
export ROS_MASTER_URI="http://localhost:$PORT"
roscore -p "$PORT" >"$DEMO/screenshots_roscore.log" 2>&1 &
PIDS+=($!)
/usr/bin/python3 -c '
import sys, time, rosgraph
for _ in range(100):
    if rosgraph.is_master_online():
        sys.exit(0)
    time.sleep(0.1)
sys.exit("[screenshots] the ROS master did not come up")'

config="$DEMO/screenshots_config.yaml"
cat "$ROOT/config/default.yaml" >"$config"
echo "publish_block_bounds: true" >>"$config"
# Slowed down: software rendering of the growing mesh shares the CPU with fusion, and the
# mid-run picture needs time to be taken.
roslaunch stereo_fusion replay.launch bag:="$BAG" config:="$config" rate:=0.25 player_required:=false rviz:=true \
  >"$DEMO/screenshots_launch.log" 2>&1 &
PIDS+=($!)

frames_fused() {
  /usr/bin/python3 - <<'PY'
import rospy
from diagnostic_msgs.msg import DiagnosticArray
rospy.init_node("screenshot_probe", anonymous=True, disable_signals=True)
try:
    msg = rospy.wait_for_message("/diagnostics", DiagnosticArray, timeout=5.0)
    for s in msg.status:
        for kv in s.values:
            if "fusion" in s.name and kv.key == "frames fused":
                print(kv.value)
                raise SystemExit(0)
except rospy.ROSException:
    pass
print(0)
PY
}
wait_frames() {
  local target="$1" waited=0
  while [ "$(frames_fused)" -lt "$target" ] && [ "$waited" -lt 600 ]; do sleep 2; waited=$((waited + 7)); done
}

wait_frames $((FRAMES / 2))
sleep 3
import -window root "$OUT/rviz_mapping.png"
echo "[screenshots] $OUT/rviz_mapping.png at $(frames_fused) frames"
wait_frames "$FRAMES"
sleep 8  # rviz draws the last update
import -window root "$OUT/rviz_final.png"
echo "[screenshots] $OUT/rviz_final.png"

# Block bounds: a second rviz on the same screen with the debug display ticked.
rosnode kill /rviz >/dev/null 2>&1 || true  # the first rviz, by name on our own master
sleep 2
sed -e '/Name: Block bounds (debug)/{n;s/Enabled: false/Enabled: true/}' "$ROOT/rviz/stereo_fusion.rviz" \
  >"$DEMO/screenshots_blocks.rviz"
rviz -d "$DEMO/screenshots_blocks.rviz" >"$DEMO/screenshots_rviz2.log" 2>&1 &
PIDS+=($!)
sleep 15  # ~block_bounds is latched: the new rviz gets the last one
import -window root "$OUT/rviz_blocks.png"
echo "[screenshots] $OUT/rviz_blocks.png"
