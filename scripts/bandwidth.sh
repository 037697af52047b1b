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
export PYENV_VERSION=system ROS_HOSTNAME=localhost
set +u
# shellcheck disable=SC1091
source "$BUILD_DIR/devel/setup.bash"
set -u

DEMO="$ROOT/.demo"
BAG="$DEMO/room_${FRAMES}.bag"
mkdir -p "$DEMO" "$ROOT/demo_output"
if [ ! -f "$BAG" ]; then
  echo "[bandwidth] generating the simulated room ($FRAMES frames, 640x480, SGBM) -> $BAG"
  "$BUILD_DIR/devel/lib/stereo_fusion/stereo_fusion_simulate" --preset room --trajectory walkthrough \
    --frames "$FRAMES" --disparity sgbm --seed 1 --out "$DEMO/room_${FRAMES}" --bag "$BAG.part"
  mv "$BAG.part" "$BAG"
fi
RESULTS="$ROOT/demo_output/bandwidth.jsonl"
rm -f "$RESULTS"

PIDS=()
cleanup() {
  for pid in "${PIDS[@]}"; do kill -INT "$pid" 2>/dev/null || true; done
  sleep 1
  for pid in "${PIDS[@]}"; do kill -KILL "$pid" 2>/dev/null || true; wait "$pid" 2>/dev/null || true; done
  PIDS=()
}
trap cleanup EXIT

for encoding in float32 compact; do
  config="$(mktemp --suffix=.yaml)"
  cat "$ROOT/config/default.yaml" >"$config"
  echo "mesh_encoding: $encoding" >>"$config"
  PORT="$(/usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("", 0)); print(s.getsockname()[1])')"
  export ROS_MASTER_URI="http://localhost:$PORT"
  roscore -p "$PORT" >"$DEMO/bandwidth_roscore.log" 2>&1 &
  PIDS+=($!)
  /usr/bin/python3 -c '
import sys, time, rosgraph
for _ in range(100):
    if rosgraph.is_master_online():
        sys.exit(0)
    time.sleep(0.1)
sys.exit("[bandwidth] the ROS master did not come up")'
  echo "[bandwidth] $encoding: replaying $BAG (log: $DEMO/bandwidth_$encoding.log)"
  roslaunch stereo_fusion replay.launch bag:="$BAG" config:="$config" player_required:=false \
    >"$DEMO/bandwidth_$encoding.log" 2>&1 &
  PIDS+=($!)
  /usr/bin/python3 "$ROOT/tools/demo/bandwidth_monitor.py" --frames "$FRAMES" \
    --duration-s "$(/usr/bin/python3 -c "print($FRAMES / $RATE_HZ)")" --label "$encoding" --json "$RESULTS" \
    /stereo_fusion/mesh_update /stereo_fusion/mesh_markers
  cleanup
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
