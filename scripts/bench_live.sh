#!/usr/bin/env bash
# Real time with everything on: the far-range room (640×480 SGBM with a real matcher's noise,
# walls 3–4.5 m away) recorded at 30 Hz and replayed at 1× into the real nodelet with carving,
# the ESDF and the planning layer at planning_publish_rate_hz, meshing at --mesh-hz, and every
# output subscribed (mesh updates and markers, occupancy grid and its updates, ESDF slice,
# occupied voxels), as rviz, a planner and a base station would. Prints the frames fused and
# dropped (by reason, and lost before the node), the latency stamp -> mesh published (p50, p99),
# the per-stage timings and the nodelet manager's CPU; the raw figures go to
# demo_output/live.json.
#   scripts/bench_live.sh [--voxel-size-m V] [--frames N] [--mesh-hz H] [--set key=value ...]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/.build}"
VOXEL=0.01
FRAMES=300
MESH_HZ=10
SETS=()
while [ $# -gt 0 ]; do
  case "$1" in
    --voxel-size-m) VOXEL="$2"; shift 2 ;;
    --frames) FRAMES="$2"; shift 2 ;;
    --mesh-hz) MESH_HZ="$2"; shift 2 ;;
    --set) SETS+=("$2"); shift 2 ;;
    -h|--help) sed -n '2,10p' "$0"; exit 0 ;;
    *) echo "bench_live.sh: unknown option $1" >&2; exit 2 ;;
  esac
done

"$ROOT/scripts/setup.sh" --targets "stereo_fusion_nodelet stereo_fusion_simulate stereo_fusion_generate_messages"
# shellcheck source=scripts/lib/ros_session.sh
source "$ROOT/scripts/lib/ros_session.sh"
ros_env
DEMO="$ROOT/.demo"
NAME="far_room_30hz_$FRAMES"
BAG="$DEMO/${NAME}_map.bag"  # tf in map (the default world_frame): older caches in world are not reused
mkdir -p "$DEMO" "$ROOT/demo_output"
if [ ! -f "$BAG" ]; then
  echo "[live] generating the far-range room ($FRAMES frames at 30 Hz, 640x480, SGBM) -> $BAG"
  "$BUILD_DIR/devel/lib/stereo_fusion/stereo_fusion_simulate" --preset hall --trajectory orbit \
    --fx 576 --baseline 0.12 --frames "$FRAMES" --rate-hz 30 --disparity sgbm \
    --matcher-noise-px 0.2 --mismatch-fraction 0.03 --seed 3 --out "$DEMO/$NAME" --bag "$BAG.part"
  mv "$BAG.part" "$BAG"
fi
config="$DEMO/live_config.yaml"
{
  cat "$ROOT/config/default.yaml"
  echo "voxel_size_m: $VOXEL"
  echo "mesh_publish_rate_hz: $MESH_HZ"
  for kv in "${SETS[@]}"; do echo "${kv%%=*}: ${kv#*=}"; done
} >"$config"

PIDS=()
trap stop_pids EXIT
start_master live "$DEMO/live_roscore.log"
echo "[live] replaying $BAG at 1x, voxel $VOXEL m, meshing at $MESH_HZ Hz (log: $DEMO/live.log)"
roslaunch stereo_fusion replay.launch bag:="$BAG" config:="$config" player_required:=false \
  start_paused:=true >"$DEMO/live.log" 2>&1 &
PIDS+=($!)
node=/stereo_fusion
/usr/bin/python3 "$ROOT/tools/demo/demo_monitor.py" --frames "$FRAMES" --launch-pid "$!" --idle-s 20 \
  --unpause /player/pause_playback --cpu-node /stereo_fusion_manager /player --json "$ROOT/demo_output/live.json" \
  --subscribe $node/mesh_update $node/mesh_markers $node/occupancy_grid $node/occupancy_grid_updates \
  $node/esdf_slice $node/occupied_voxels
echo "[live] $FRAMES frames at 30 Hz, voxel $VOXEL m: demo_output/live.json"
