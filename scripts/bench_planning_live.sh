#!/usr/bin/env bash
# The planning interface live: replays the demo room (640×480 SGBM) into the real nodelet at 30 Hz
# (the 10 Hz bag at --rate 3) while stereo_fusion_planning_probe calls ~get_distance with 1, 1 000
# and 100 000 points (round robin at --calls-hz) and follows ~occupancy_grid with its updates.
# Prints the round trip p50 / p99 / max per batch size, the grid's bytes per second with updates
# and as full grids only, and the node's frames fused and dropped; the raw figures go to
# demo_output/planning_live.json.
#   scripts/bench_planning_live.sh [--frames N] [--rate R] [--calls-hz H] [--voxel-size-m V]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/.build}"
FRAMES=300
RATE=3        # the bag is recorded at 10 Hz: 3 = 30 Hz
CALLS_HZ=10
VOXEL=0.02
while [ $# -gt 0 ]; do
  case "$1" in
    --frames) FRAMES="$2"; shift 2 ;;
    --rate) RATE="$2"; shift 2 ;;
    --calls-hz) CALLS_HZ="$2"; shift 2 ;;
    --voxel-size-m) VOXEL="$2"; shift 2 ;;
    -h|--help) sed -n '2,8p' "$0"; exit 0 ;;
    *) echo "bench_planning_live.sh: unknown option $1" >&2; exit 2 ;;
  esac
done

"$ROOT/scripts/setup.sh" --targets "stereo_fusion_nodelet stereo_fusion_simulate stereo_fusion_generate_messages stereo_fusion_planning_probe"
# shellcheck source=scripts/lib/ros_session.sh
source "$ROOT/scripts/lib/ros_session.sh"
ros_env
ensure_demo_bag "$FRAMES" planning-live
mkdir -p "$ROOT/demo_output"
RESULT="$ROOT/demo_output/planning_live.json"
PIDS=()
trap stop_pids EXIT

config="$DEMO/planning_live_config.yaml"
cat "$ROOT/config/default.yaml" >"$config"
echo "voxel_size_m: $VOXEL" >>"$config"
start_master planning-live "$DEMO/planning_live_roscore.log"
echo "[planning-live] replaying $BAG at ${RATE}x (log: $DEMO/planning_live.log)"
roslaunch stereo_fusion replay.launch bag:="$BAG" config:="$config" rate:="$RATE" \
  player_required:=false start_paused:=true >"$DEMO/planning_live.log" 2>&1 &
PIDS+=($!)
duration="$(/usr/bin/python3 -c "print($FRAMES / (10.0 * $RATE))")"
"$BUILD_DIR/devel/lib/stereo_fusion/stereo_fusion_planning_probe" --duration-s "$duration" \
  --calls-hz "$CALLS_HZ" --unpause /player/pause_playback --json "$RESULT"
echo "[planning-live] $FRAMES frames at $(/usr/bin/python3 -c "print(10 * $RATE)") Hz, voxel $VOXEL m; $RESULT"
