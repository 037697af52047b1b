#!/usr/bin/env bash
# Bandwidth of the robot's outputs on the demo sequence (the simulated room, 100 frames at 10 Hz):
# replays the bag through stereo_fusion once per mesh encoding (float32, compact) and counts the
# serialized bytes of ~mesh_update and ~mesh_markers. Prints a table of bytes/s over the bag's
# duration; the raw numbers go to demo_output/bandwidth.jsonl.
#   scripts/bandwidth.sh [--frames N]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/.build}"
FRAMES=100
RATE_HZ=10  # the simulator's default frame rate: the bag lasts FRAMES / RATE_HZ seconds
while [ $# -gt 0 ]; do
  case "$1" in
    --frames) FRAMES="$2"; shift 2 ;;
    -h|--help) sed -n '2,6p' "$0"; exit 0 ;;
    *) echo "bandwidth.sh: unknown option $1" >&2; exit 2 ;;
  esac
done

"$ROOT/scripts/setup.sh"
# shellcheck source=scripts/lib/ros_session.sh
source "$ROOT/scripts/lib/ros_session.sh"
ros_env
ensure_demo_bag "$FRAMES" bandwidth
mkdir -p "$ROOT/demo_output"
RESULTS="$ROOT/demo_output/bandwidth.jsonl"
rm -f "$RESULTS"

PIDS=()
trap stop_pids EXIT

for encoding in float32 compact; do
  config="$(mktemp --suffix=.yaml)"
  cat "$ROOT/config/default.yaml" >"$config"
  echo "mesh_encoding: $encoding" >>"$config"
  start_master bandwidth "$DEMO/bandwidth_roscore.log"
  echo "[bandwidth] $encoding: replaying $BAG (log: $DEMO/bandwidth_$encoding.log)"
  roslaunch stereo_fusion replay.launch bag:="$BAG" config:="$config" player_required:=false \
    >"$DEMO/bandwidth_$encoding.log" 2>&1 &
  PIDS+=($!)
  /usr/bin/python3 "$ROOT/tools/demo/bandwidth_monitor.py" --frames "$FRAMES" \
    --duration-s "$(/usr/bin/python3 -c "print($FRAMES / $RATE_HZ)")" --label "$encoding" --json "$RESULTS" \
    /stereo_fusion/mesh_update /stereo_fusion/mesh_markers
  stop_pids
  rm -f "$config"
done

/usr/bin/python3 - "$RESULTS" <<'PY'
import json, sys
rows = [json.loads(line) for line in open(sys.argv[1])]
by = {r["label"]: r for r in rows}
print()
print("| topic | float32 (B/s) | compact (B/s) | saving |")
print("|---|---:|---:|---:|")
for topic in ("/stereo_fusion/mesh_update", "/stereo_fusion/mesh_markers"):
    a = by["float32"]["topics"][topic]["bytes_per_s"]
    b = by["compact"]["topics"][topic]["bytes_per_s"]
    print(f"| `{topic}` | {a:,.0f} | {b:,.0f} | {100 * (1 - b / a) if a else 0:.0f} % |")
print(f"frames fused: float32 {by['float32']['frames_fused']}, compact {by['compact']['frames_fused']}")
PY
