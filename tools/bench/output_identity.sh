#!/usr/bin/env bash
# Every output file of the offline fuser on a set of scenes, as SHA-256 lines: what a pure
# restructuring must leave byte-identical. Run it with the binary before and after, then diff:
#   tools/bench/output_identity.sh <stereo_fusion_fuse> <work-dir> > before.sha256
#   tools/bench/output_identity.sh <other stereo_fusion_fuse> <work-dir2> > after.sha256
#   diff before.sha256 after.sha256
# Scenes: the bench room (with texture patches too), the far-range hall, a drifting two-lap
# orbit fused again after the last frame at its SLAM trajectory, and the real sequences
# redkitchen and kitti-stereo-51 (../shared/data, skipped with a note when absent). The
# simulated scenes are made once under <work-dir>/data by the simulator beside the fuser.
set -euo pipefail
FUSE="$(realpath "$1")"
WORK="$2"
SIM="$(dirname "$FUSE")/stereo_fusion_simulate"
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
DATA="${STEREO_FUSION_DATA:-$ROOT/../shared/data}"
mkdir -p "$WORK/data"

simulate() {  # name, simulator arguments...
  local name="$1"; shift
  [ -f "$WORK/data/$name/poses.txt" ] || "$SIM" --out "$WORK/data/$name" "$@" >&2
}
simulate room --preset room --trajectory walkthrough --frames 40 --seed 1
simulate hall --preset hall --trajectory orbit --fx 576 --baseline 0.12 --frames 30 --seed 1 \
  --matcher-noise-px 0.2 --mismatch-fraction 0.03
simulate drift --preset room --trajectory orbit --revolutions 2 --frames 60 --seed 2 \
  --drift 6,0.15 --keyframe-every 5

run() {  # name, input, fuser arguments...
  local name="$1" input="$2"; shift 2
  if [ ! -e "$input" ]; then echo "[identity] $name: $input absent, skipped" >&2; return; fi
  local out="$WORK/out/$name"
  rm -rf "$out"
  mkdir -p "$out"
  echo "[identity] $name" >&2
  # IDENTITY_EXTRA_ARGS: appended to every run (e.g. "--set max_map_memory_mb=4": paging must
  # leave every output as it is).
  # shellcheck disable=SC2086
  "$FUSE" "$input" "$out" --quiet --save-map "$out/map.sfmap" "$@" ${IDENTITY_EXTRA_ARGS:-} >&2
  # stats.json holds timings and the machine's figures: everything else is compared.
  (cd "$out" && find . -type f ! -name stats.json | LC_ALL=C sort | xargs sha256sum |
     sed "s|  \./|  $name/|")
}
run room "$WORK/data/room"
run room_textured "$WORK/data/room" --set texture=patches --mesh-every 5
run hall "$WORK/data/hall" --set voxel_size_m=0.04 --esdf-every 3
run drift "$WORK/data/drift" --trajectory "$WORK/data/drift/trajectory.txt"
run redkitchen "$DATA/redkitchen-0-297" --frames 60
run kitti "$DATA/kitti-stereo-51" --frames 30 --set voxel_size_m=0.1 --set max_depth_m=30
