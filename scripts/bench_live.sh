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
#                         [--rviz plugin|markers|none]
# --rviz plugin / markers: a real rviz on a virtual X screen (xvfb-run, Mesa's software OpenGL)
# for the whole replay, showing the mesh alone, through the display stereo_fusion/Mesh
# (~mesh_update) or through the MarkerArray display (~mesh_markers); rviz, not the monitor, is
# then the mesh's subscriber, and its CPU is measured beside the manager's. none (the default):
# no rviz, the monitor subscribes to both mesh topics.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/.build}"
VOXEL=0.01
FRAMES=300
MESH_HZ=10
SETS=()
RVIZ=none
while [ $# -gt 0 ]; do
  case "$1" in
    --voxel-size-m) VOXEL="$2"; shift 2 ;;
    --frames) FRAMES="$2"; shift 2 ;;
    --mesh-hz) MESH_HZ="$2"; shift 2 ;;
    --set) SETS+=("$2"); shift 2 ;;
    --rviz) RVIZ="$2"; shift 2 ;;
    -h|--help) sed -n '2,16p' "$0"; exit 0 ;;
    *) echo "bench_live.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
case "$RVIZ" in
  plugin | markers | none) ;;
  *) echo "bench_live.sh: --rviz takes plugin, markers or none, not '$RVIZ'" >&2; exit 2 ;;
esac

TARGETS="stereo_fusion_nodelet stereo_fusion_simulate stereo_fusion_generate_messages"
if [ "$RVIZ" = plugin ]; then TARGETS+=" stereo_fusion_rviz"; fi
"$ROOT/scripts/setup.sh" --targets "$TARGETS"
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

# shellcheck source=scripts/lib/bench_rviz.sh
source "$ROOT/scripts/lib/bench_rviz.sh"

PIDS=()
trap 'stop_bench_rviz; stop_pids' EXIT
start_master live "$DEMO/live_roscore.log"
echo "[live] replaying $BAG at 1x, voxel $VOXEL m, meshing at $MESH_HZ Hz, rviz: $RVIZ (log: $DEMO/live.log)"
roslaunch stereo_fusion replay.launch bag:="$BAG" config:="$config" player_required:=false \
  start_paused:=true >"$DEMO/live.log" 2>&1 &
launch_pid=$!
PIDS+=("$launch_pid")
node=/stereo_fusion
outputs=("$node/occupancy_grid" "$node/occupancy_grid_updates" "$node/esdf_slice" "$node/occupied_voxels")
cpu_nodes=(/stereo_fusion_manager /player)
if [ "$RVIZ" = none ]; then
  outputs+=("$node/mesh_update" "$node/mesh_markers")
else
  # rviz joins once the replay's parameters (use_sim_time) are set and the node is up; the
  # player stays paused until rviz subscribed to its mesh topic.
  mesh_topic=$node/mesh_update
  if [ "$RVIZ" = markers ]; then mesh_topic=$node/mesh_markers; fi
  start_bench_rviz "$RVIZ" "$mesh_topic" "$DEMO/live_rviz" "$launch_pid"
  cpu_nodes+=("$BENCH_RVIZ_NODE")
fi
/usr/bin/python3 "$ROOT/tools/demo/demo_monitor.py" --frames "$FRAMES" --launch-pid "$launch_pid" --idle-s 20 \
  --unpause /player/pause_playback --cpu-node "${cpu_nodes[@]}" --json "$ROOT/demo_output/live.json" \
  --subscribe "${outputs[@]}"
if [ "$RVIZ" != none ]; then stop_bench_rviz; fi
echo "[live] $FRAMES frames at 30 Hz, voxel $VOXEL m, rviz: $RVIZ: demo_output/live.json"
