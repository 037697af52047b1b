#!/usr/bin/env bash
# The planning layer's benchmark: per frame, what recording the free space costs beside lookup +
# fusion; per update, what the ESDF costs when updated after every frame and after every 10th;
# a batch rebuild; a 100 000-point query; memory; and the ESDF's errors against the brute force
# and the true surface (stereo_fusion_evaluate_esdf). One fuser run per row, one after another.
#   scripts/bench_planning.sh [--set key=value ...] SEQ [SEQ ...]
# SEQ: a dataset folder (with gt_mesh.ply the accuracy is scored), or room / hall / noisy-hall:
# the simulated bench room (100 SGBM frames), the far-range hall (60 SGBM frames) or the hall
# with noisy disparities (σ 0.25 px, 3 % outliers), generated once into .bench/.
# Timings depend on the machine's load: compare ratios from one run, not runs across days.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="${BUILD_DIR:-$ROOT/.build}/devel/lib/stereo_fusion"
WORK="$ROOT/.bench/planning"
SETS=()
SEQS=()
while [ $# -gt 0 ]; do
  case "$1" in
    --set) SETS+=(--set "$2"); shift 2 ;;
    -h|--help) sed -n 2,10p "$0"; exit 0 ;;
    *) SEQS+=("$1"); shift ;;
  esac
done
[ ${#SEQS[@]} -gt 0 ] || { echo "usage: scripts/bench_planning.sh [--set key=value ...] SEQ [SEQ ...]" >&2; exit 2; }
"$ROOT/scripts/setup.sh" --targets "stereo_fusion_fuse stereo_fusion_simulate stereo_fusion_evaluate_esdf" >&2
mkdir -p "$WORK"

simulated() {  # name → folder, generated once
  local name="$1" dir="$WORK/$1"
  if [ ! -f "$dir/poses.txt" ]; then
    case "$name" in
      room) args=(--preset room --trajectory walkthrough --frames 100 --disparity sgbm --seed 1) ;;
      hall) args=(--preset hall --trajectory orbit --fx 576 --baseline 0.12 --frames 60 --disparity sgbm --seed 1) ;;
      noisy-hall) args=(--preset hall --trajectory orbit --fx 576 --baseline 0.12 --frames 60 --disparity noisy
                        --noise-px 0.25 --outlier-fraction 0.03 --seed 2) ;;
    esac
    echo "[bench] simulating $name" >&2
    "$BIN/stereo_fusion_simulate" "${args[@]}" --out "$dir" >&2
  fi
  echo "$dir"
}

printf '%-28s %7s %7s %9s %9s %9s %9s %8s %7s %7s %7s %8s %8s\n' sequence "l+f" free "free/l+f" "esdf/1" "esdf/10" \
  "esdf/fr" rebuild q100k map_MB free_MB esdf_MB "bf_max_m"
for s in "${SEQS[@]}"; do
  case "$s" in room|hall|noisy-hall) seq="$(simulated "$s")" ;; *) seq="$s" ;; esac
  name="$(basename "$seq")"
  for every in 1 10; do
    "$BIN/stereo_fusion_fuse" "$seq" "$WORK/out_${name}_e$every" --quiet --time-planning --esdf-every "$every" "${SETS[@]}" >&2
  done
  bf="-"
  if "$BIN/stereo_fusion_evaluate_esdf" "$WORK/out_${name}_e10/esdf.ply" $([ -f "$seq/gt_mesh.ply" ] && echo "$seq") \
       --json "$WORK/esdf_$name.json" > "$WORK/esdf_$name.txt"; then
    bf="$(/usr/bin/python3 -c "import json; print('%.4f' % json.load(open('$WORK/esdf_$name.json'))['brute_force'][-1]['max_m'])")"
  fi
  /usr/bin/python3 - "$WORK/out_${name}_e1/stats.json" "$WORK/out_${name}_e10/stats.json" "$name" "$bf" <<'PY'
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
t = a['timings_ms']; lf = t['lookup']['p50'] + t['fusion']['p50']; fs = t['free_space']['p50']
e10 = b['timings_ms']['esdf']['mean']
m = a['memory']
print('%-28s %7.2f %7.2f %8.0f%% %9.2f %9.2f %9.2f %8.0f %7.1f %7.1f %7.2f %8.2f %8s' % (
    sys.argv[3][:28], lf, fs, 100 * fs / lf, t['esdf']['p50'], e10, e10 / 10, a['planning']['rebuild_ms'],
    a['planning']['query_100k_ms'], m['megabytes'], m['free_space_megabytes'], m['esdf_megabytes'], sys.argv[4]))
PY
done
echo "(ms p50 per frame unless noted: esdf/1 per update after every frame, esdf/10 mean per update after every 10th, esdf/fr that per frame; rebuild and q100k: one batch rebuild, one 100 000-point query; bf_max_m: largest ESDF error against the brute force; accuracy tables in $WORK/esdf_*.txt)"
