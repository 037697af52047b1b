#!/usr/bin/env bash
# Robust fusion against noisy far-range stereo (ContradictionFilter): each sequence fused with
# contradiction_filter off and on (and Open3D's ScalableTSDFVolume on the simulated far rooms),
# scored as doc/performance.md "Noisy far-range stereo" reports it.
#   scripts/bench_robust.sh [--real]
# Simulated far rooms with a real matcher's errors (σ_d ≈ 0.25 px, 3–4 % mismatches of 1–3 px
# agreeing across 5 neighbouring frames), scored with walls solid (--accuracy-against seen);
# the bench room and the hall scored against all of their truth; with --real also redkitchen
# and kitti-stereo-51 (../shared/data), even frames fused, odd frames held out.
# Prints: median, p90, share beyond 10 cm of the accuracy, then completeness (ground truth) or
# median, p90, covered, floating (held out).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="${BUILD_DIR:-$ROOT/.build}/devel/lib/stereo_fusion"
WORK="$ROOT/.bench/robust"
REAL=0
[ "${1:-}" = "--real" ] && REAL=1
"$ROOT/scripts/setup.sh" --targets "stereo_fusion_fuse stereo_fusion_simulate stereo_fusion_evaluate" >&2
mkdir -p "$WORK"

simulate() {  # name args... → $WORK/name, generated once
  local name="$1"; shift
  [ -f "$WORK/$name/poses.txt" ] || "$BIN/stereo_fusion_simulate" "$@" --out "$WORK/$name" >&2
}
simulate far-room-3 --preset hall --trajectory orbit --fx 576 --baseline 0.12 --frames 60 \
  --disparity sgbm --matcher-noise-px 0.2 --mismatch-fraction 0.03 --seed 3
simulate far-room-4 --preset hall --trajectory orbit --fx 576 --baseline 0.12 --frames 60 \
  --disparity sgbm --matcher-noise-px 0.25 --mismatch-fraction 0.04 --seed 4
simulate room --preset room --trajectory walkthrough --frames 100 --disparity sgbm --seed 1
simulate hall --preset hall --trajectory orbit --fx 576 --baseline 0.12 --frames 60 --disparity sgbm --seed 1

scores() {  # evaluator arguments → the figures on one line
  "$BIN/stereo_fusion_evaluate" "$@" 2>/dev/null |
    grep -E "^  (median|p90|share > 10|completeness \(visible|completeness \(measured|floating)" |
    head -8 | awk '{printf "%s%s ", $(NF-1), $NF} END {print ""}'
}
fuse() {  # seq out filter [--set ...]
  local seq="$1" out="$2" filter="$3"; shift 3
  "$BIN/stereo_fusion_fuse" "$seq" "$out" --quiet --set contradiction_filter="$filter" "$@" >&2
}

for name in far-room-3 far-room-4 room hall; do
  seq="$WORK/$name"
  case "$name" in far-room-*) against=(--accuracy-against seen) ;; *) against=() ;; esac
  for filter in false true; do
    fuse "$seq" "$WORK/out_${name}_$filter" "$filter"
    echo "$name contradiction_filter=$filter: $(scores "$WORK/out_${name}_$filter/mesh.ply" "$seq" --tolerance-m 0.05 "${against[@]}")"
  done
  case "$name" in far-room-*)
    /usr/bin/python3 "$ROOT/tools/bench/open3d_fuse.py" "$seq" "$WORK/open3d_$name.ply" 0.02 0.08 8 >/dev/null
    echo "$name Open3D: $(scores "$WORK/open3d_$name.ply" "$seq" --tolerance-m 0.05 "${against[@]}")" ;;
  esac
done

if [ "$REAL" = 1 ]; then
  even() {  # a dataset folder of SRC's even frames (symlinks), renumbered
    local src="$1" dst="$2"
    rm -rf "$dst"; mkdir -p "$dst"; ln -s "$src/calibration.yaml" "$dst/calibration.yaml"
    awk 'NR % 2 == 1' "$src/poses.txt" > "$dst/poses.txt"
    for d in disparity color right; do
      [ -d "$src/$d" ] || continue; mkdir -p "$dst/$d"; local i=0
      for f in $(ls "$src/$d" | sort); do
        if [ $((10#${f%.*} % 2)) -eq 0 ]; then ln -s "$src/$d/$f" "$dst/$d/$(printf %06d.%s $i "${f##*.}")"; i=$((i + 1)); fi
      done
    done
  }
  DATA="$ROOT/../shared/data"
  even "$DATA/redkitchen-0-297" "$WORK/redkitchen-even"
  even "$DATA/kitti-stereo-51" "$WORK/kitti-even"
  for filter in false true; do
    fuse "$WORK/redkitchen-even" "$WORK/out_redkitchen_$filter" "$filter"
    echo "redkitchen held out, contradiction_filter=$filter: $(scores "$WORK/out_redkitchen_$filter/mesh.ply" "$DATA/redkitchen-0-297" --held-out odd)"
    fuse "$WORK/kitti-even" "$WORK/out_kitti_$filter" "$filter" --set voxel_size_m=0.1 --set max_depth_m=25
    echo "kitti-stereo-51 held out, contradiction_filter=$filter: $(scores "$WORK/out_kitti_$filter/mesh.ply" "$DATA/kitti-stereo-51" --held-out odd --max-depth-m 25 --tolerance-m 0.2)"
  done
fi
