#!/usr/bin/env bash
# Soak: fuses an endless simulated corridor (the camera keeps moving, so new space keeps being
# allocated) through the same Mapper code as the nodelet and the offline fuser, twice — without
# a memory bound and with one — sampling the process' resident memory (VmRSS) every K frames.
# With the bound the RSS must plateau. Writes <out>/unbounded.csv, <out>/bounded.csv and the
# curves <out>/rss.png, prints RSS at start / middle / end of both runs, and exits non-zero if
# the bounded run's RSS still grows over its second half by more than 10 %.
#   scripts/soak.sh [--frames N] [--sample-every K] [--max-blocks B] [--voxel M] [--out DIR]
# Defaults: 10000 frames, every 100, max_blocks 2000, 4 cm voxels, 160×120 images, .soak/.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="${BUILD_DIR:-$ROOT/.build}/devel/lib/stereo_fusion/stereo_fusion_soak"
FRAMES=10000
EVERY=100
MAX_BLOCKS=2000
VOXEL=0.04
OUT="$ROOT/.soak"
while [ $# -gt 0 ]; do
  case "$1" in
    --frames) FRAMES="$2"; shift 2 ;;
    --sample-every) EVERY="$2"; shift 2 ;;
    --max-blocks) MAX_BLOCKS="$2"; shift 2 ;;
    --voxel) VOXEL="$2"; shift 2 ;;
    --out) OUT="$2"; shift 2 ;;
    *) echo "soak.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
"$ROOT/scripts/setup.sh" --targets stereo_fusion_soak >&2
mkdir -p "$OUT"
common=(--frames "$FRAMES" --sample-every "$EVERY" --set "voxel_size_m=$VOXEL" --set num_threads=2)
echo "[soak] unbounded: $FRAMES frames, voxel $VOXEL m"
"$BIN" --csv "$OUT/unbounded.csv" "${common[@]}"
echo "[soak] bounded: max_blocks=$MAX_BLOCKS"
"$BIN" --csv "$OUT/bounded.csv" "${common[@]}" --set "max_blocks=$MAX_BLOCKS"
"$BIN" --plot "$OUT/rss.png" "unbounded=$OUT/unbounded.csv" "bounded (max_blocks=$MAX_BLOCKS)=$OUT/bounded.csv"
echo "[soak] wrote $OUT/unbounded.csv, $OUT/bounded.csv, $OUT/rss.png"
# Plateau check on the bounded run: RSS at the end vs at the middle sample.
awk -F, 'NR > 1 { rss[n++] = $2 } END {
  mid = rss[int(n / 2)]; last = rss[n - 1];
  growth = (last - mid) / mid;
  printf "[soak] bounded RSS middle %.1f MiB, end %.1f MiB: %+.1f %% over the second half\n", mid, last, 100 * growth;
  exit (growth > 0.10) ? 1 : 0 }' "$OUT/bounded.csv"
