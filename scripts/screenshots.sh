#!/usr/bin/env bash
# rviz screenshots for README.md and doc/, made headless: installs rviz, Xvfb and ImageMagick if missing
# (scripts/setup.sh --screenshots), replays the demo bag (the simulated room) through
# stereo_fusion with rviz on a virtual X display (software OpenGL, Mesa llvmpipe) and captures
# the screen:
#   doc/images/rviz_mapping.png   mid-run: mesh, camera path, current frustum
#   doc/images/rviz_final.png     after the last frame
#   doc/images/rviz_blocks.png    the same with the block bounds (debug) shown
#   doc/images/rviz_planning.png  the planning layer alone: occupancy grid, ESDF slice, occupied cells
#   doc/images/rviz_mesh_plugin.png  the mesh alone through the display stereo_fusion/Mesh, in an rviz
#                                 started after the last frame (it fetched ~get_full_mesh)
#   scripts/screenshots.sh [--frames N]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/.build}"
FRAMES=100
while [ $# -gt 0 ]; do
  case "$1" in
    --frames) FRAMES="$2"; shift 2 ;;
    --inside-xvfb) INSIDE_XVFB=1; shift ;;
    -h|--help) sed -n '2,11p' "$0"; exit 0 ;;
    *) echo "screenshots.sh: unknown option $1" >&2; exit 2 ;;
  esac
done

if [ -z "${INSIDE_XVFB:-}" ]; then
  "$ROOT/scripts/setup.sh" --screenshots
  # One virtual screen for everything below; rviz renders with Mesa's software OpenGL.
  export LIBGL_ALWAYS_SOFTWARE=1
  exec xvfb-run -a -s "-screen 0 1280x800x24" "$0" --frames "$FRAMES" --inside-xvfb
fi

# shellcheck source=scripts/lib/ros_session.sh
source "$ROOT/scripts/lib/ros_session.sh"
ros_env
ensure_demo_bag "$FRAMES" screenshots
OUT="$ROOT/doc/images"
mkdir -p "$OUT"

PIDS=()
trap stop_pids EXIT
start_master screenshots "$DEMO/screenshots_roscore.log"

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
rviz_pid=$!
PIDS+=("$rviz_pid")
sleep 15  # ~block_bounds is latched: the new rviz gets the last one
import -window root "$OUT/rviz_blocks.png"
echo "[screenshots] $OUT/rviz_blocks.png"

# The planning layer: the mesh hidden, the occupied cells shown beside the grid and the slice (a
# new subscriber gets the grid when it connects; the clouds come at planning_publish_rate_hz).
rosnode kill /rviz >/dev/null 2>&1 || true
kill -INT "$rviz_pid" 2>/dev/null || true  # the rviz started above, by its PID
sleep 2
sed -e '/Name: Mesh$/{n;s/Enabled: true/Enabled: false/}' \
  -e '/Name: Occupied cells$/{n;s/Enabled: false/Enabled: true/}' \
  "$ROOT/rviz/stereo_fusion.rviz" >"$DEMO/screenshots_planning.rviz"
rviz -d "$DEMO/screenshots_planning.rviz" >"$DEMO/screenshots_rviz3.log" 2>&1 &
rviz_pid=$!
PIDS+=("$rviz_pid")
sleep 15
import -window root "$OUT/rviz_planning.png"
echo "[screenshots] $OUT/rviz_planning.png"

# The mesh alone through the plugin (every display but the grid and the mesh off), in an rviz that
# joins after the last frame: what it draws came from ~get_full_mesh.
kill -INT "$rviz_pid" 2>/dev/null || true
sleep 2
sed -E -e '/Name: (Camera path|Camera frustum|Occupancy grid|ESDF slice|TF)$/{n;s/Enabled: true/Enabled: false/}' \
  "$ROOT/rviz/stereo_fusion.rviz" >"$DEMO/screenshots_mesh.rviz"
rviz -d "$DEMO/screenshots_mesh.rviz" >"$DEMO/screenshots_rviz4.log" 2>&1 &
PIDS+=($!)
sleep 15
import -window root "$OUT/rviz_mesh_plugin.png"
echo "[screenshots] $OUT/rviz_mesh_plugin.png"
