#!/usr/bin/env bash
# Issue 49's building bench: the offline fuser on one sequence uncapped and capped
# (max_map_memory_mb), the resident set of each run sampled every 0.5 s, every output of the
# two runs compared byte for byte, and the figures (wall time, peak RSS, stats.json's paging
# and timings) with a plot of RSS over time.
#   tools/bench/building_bench.sh <seq-folder> <work-dir> [cap-mb (64)] [voxel-size-m (0.01)]
# The sequence: scripts/simulate.sh --preset building --seed 0 --out <seq-folder> (one lap).
# <work-dir> gets the runs' outputs (large: mesh.ply and the map file of each run), their logs
# and samples; the figures, the CSVs and the plot go to $RESULTS (default
# tools/bench/building_bench/). The capped run's page store is $STORE_DIR (default
# <work-dir>/store, emptied first). Builds stereo_fusion_fuse (Release, one job: the machine
# is shared) into $BUILD_DIR (default <repo>/.build) and runs the binary that scripts/fuse.sh
# runs, directly, so the sampled PID is the fuser itself. Runs one after the other.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
SEQ="$(realpath "$1")"
WORK="$(realpath -m "$2")"
CAP_MB="${3:-64}"
VOXEL="${4:-0.01}"
BUILD_DIR="${BUILD_DIR:-$ROOT/.build}"
RESULTS="$(realpath -m "${RESULTS:-$ROOT/tools/bench/building_bench}")"
STORE_DIR="$(realpath -m "${STORE_DIR:-$WORK/store}")"
FUSE="$BUILD_DIR/devel/lib/stereo_fusion/stereo_fusion_fuse"
PY=/usr/bin/python3  # Debian's, with python3-matplotlib for the plot
[ -f "$SEQ/poses.txt" ] || { echo "building_bench: $SEQ is not a sequence folder" >&2; exit 2; }
"$PY" -c "import matplotlib" 2>/dev/null ||
  { echo "building_bench: the plot needs Debian's python3-matplotlib (apt-get install -y python3-matplotlib)" >&2; exit 2; }

"$ROOT/scripts/setup.sh" --no-build >&2
if [ ! -f "$BUILD_DIR/CMakeCache.txt" ]; then
  PYENV_VERSION=system cmake -S "$ROOT" -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release \
    -DPYTHON_EXECUTABLE=/usr/bin/python3 -DPython3_EXECUTABLE=/usr/bin/python3 \
    -DCATKIN_ENABLE_TESTING=ON >"$BUILD_DIR.configure.log" 2>&1 \
    || { cat "$BUILD_DIR.configure.log"; exit 1; }
fi
PYENV_VERSION=system cmake --build "$BUILD_DIR" -j1 --target stereo_fusion_fuse >&2
mkdir -p "$WORK" "$RESULTS"

run() {  # name, fuser arguments after <seq> <out>...
  local name="$1"; shift
  local out="$WORK/$name"
  rm -rf "$out"
  mkdir -p "$out"
  echo "[bench] $name: $FUSE $SEQ $out $*" >&2
  local start end pid
  start=$(date +%s.%N)
  "$FUSE" "$SEQ" "$out" --set "voxel_size_m=$VOXEL" --save-map "$out/map.sfmap" "$@" \
    >"$WORK/$name.log" 2>&1 &
  pid=$!
  # The fuser's own PID (not a wrapper's): what pgrep finds for its command line, once the
  # background shell has exec'd it.
  local tries=0
  until pgrep -f -x "$FUSE $SEQ $out .*" | grep -qx "$pid"; do
    ((++tries < 100)) || { echo "[bench] pgrep does not find the fuser ($pid)" >&2; exit 1; }
    sleep 0.01
  done
  "$PY" "$ROOT/tools/bench/rss_sample.py" --pid "$pid" --csv "$WORK/${name}_rss.csv" \
    --events "$WORK/${name}_events.csv" --interval 0.5 --frames-dir "$SEQ/disparity" \
    --out-dir "$out" ${STORE:+--store-dir "$STORE"} &
  local sampler=$!
  local status=0
  wait "$pid" || status=$?
  end=$(date +%s.%N)
  wait "$sampler" || true
  echo "$start $end $status" >"$WORK/$name.wall"
  echo "[bench] $name: exit $status, $(awk "BEGIN {print $end - $start}") s" >&2
  ((status == 0)) || { tail -n 20 "$WORK/$name.log" >&2; exit 1; }
}

STORE="" run uncapped
rm -rf "$STORE_DIR"
mkdir -p "$STORE_DIR"
STORE="$STORE_DIR" run capped --set "max_map_memory_mb=$CAP_MB" --set "map_store_path=$STORE_DIR"

# Every output but stats.json (timings and the machine's figures), byte for byte.
{
  echo "file,bytes,cmp"
  (cd "$WORK/uncapped" && find . -type f ! -name stats.json | LC_ALL=C sort) | while read -r f; do
    f="${f#./}"
    if cmp -s "$WORK/uncapped/$f" "$WORK/capped/$f"; then r=identical; else r=DIFFERENT; fi
    echo "$f,$(stat -c %s "$WORK/uncapped/$f"),$r"
  done
  (cd "$WORK/capped" && find . -type f ! -name stats.json | LC_ALL=C sort) | while read -r f; do
    [ -e "$WORK/uncapped/${f#./}" ] || echo "${f#./},,only in capped"
  done
} >"$WORK/cmp.csv"
cat "$WORK/cmp.csv" >&2

cp "$WORK/uncapped_rss.csv" "$WORK/capped_rss.csv" "$WORK/uncapped_events.csv" \
  "$WORK/capped_events.csv" "$WORK/cmp.csv" "$RESULTS/"
cp "$WORK/uncapped/stats.json" "$RESULTS/uncapped_stats.json"
cp "$WORK/capped/stats.json" "$RESULTS/capped_stats.json"
"$PY" "$ROOT/tools/bench/building_bench_report.py" "$WORK" "$RESULTS" "$CAP_MB"
