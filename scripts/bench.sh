#!/usr/bin/env bash
# The benchmark: stereo_fusion (accelerated and naive lookup) and Open3D's ScalableTSDFVolume
# on the same simulated 640×480 SGBM sequence, at 1, 2 and 4 cm voxels with the same truncation
# (4 voxels); every mesh scored by scripts/evaluate.sh against the ground truth. Prints
# per-stage medians (ms), fps, blocks, MB (by level) and accuracy side by side, our total with
# one core kept busy by another process, and memory against a dense voxel grid.
#   scripts/bench.sh [--preset room|hall] [--voxels "0.01 0.02 0.04"] [--frames N] [--reuse]
# room (default): the furnished room, a 100-frame walkthrough, f = 525 px, b = 0.10 m.
# hall: the far-range class (walls 3–4.5 m away), a 60-frame orbit, f = 576 px, b = 0.12 m.
# --reuse prints the table from the outputs of an earlier run without running anything.
# Timings depend on the machine's load: compare ratios from one run, not runs across days.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="${BUILD_DIR:-$ROOT/.build}/devel/lib/stereo_fusion"
VOXELS="0.01 0.02 0.04"
PRESET=room
FRAMES=""
REUSE=0
while [ $# -gt 0 ]; do
  case "$1" in
    --preset) PRESET="$2"; shift 2 ;;
    --voxels) VOXELS="$2"; shift 2 ;;
    --frames) FRAMES="$2"; shift 2 ;;
    --reuse) REUSE=1; shift ;;
    *) echo "bench.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
"$ROOT/scripts/setup.sh" --targets "stereo_fusion_fuse stereo_fusion_simulate stereo_fusion_evaluate" >&2
if ! /usr/bin/python3 -c "import open3d, cv2, numpy" 2>/dev/null; then
  echo "[bench] installing Open3D, OpenCV and NumPy for Debian's python3" >&2
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends \
    python3-open3d python3-opencv python3-numpy >/dev/null
fi
case "$PRESET" in
  room) FRAMES="${FRAMES:-100}"; SIM_ARGS=(--preset room --trajectory walkthrough) ;;
  hall) FRAMES="${FRAMES:-60}"; SIM_ARGS=(--preset hall --trajectory orbit --fx 576 --baseline 0.12) ;;
  *) echo "bench.sh: unknown preset $PRESET (room, hall)" >&2; exit 2 ;;
esac
WORK="$ROOT/.bench"
SEQ="$WORK/${PRESET}_sgbm_${FRAMES}"
mkdir -p "$WORK"
if [ ! -f "$SEQ/poses.txt" ]; then
  echo "[bench] generating the $PRESET sequence ($FRAMES frames, SGBM) in $SEQ" >&2
  "$BIN/stereo_fusion_simulate" "${SIM_ARGS[@]}" --frames "$FRAMES" --disparity sgbm --seed 1 --out "$SEQ" >&2
fi
json() { /usr/bin/python3 -c "import json,sys; d=json.load(open('$1')); print($2)"; }
rows=()
for v in $VOXELS; do
  out="$WORK/out_${PRESET}_$v"
  tol=$(/usr/bin/python3 -c "print(max(0.05, 2*$v))")
  rows+=("$v|$out|$tol")
  if [ "$REUSE" = 1 ]; then continue; fi
  mkdir -p "$out"
  echo "[bench] voxel $v m: stereo_fusion (accelerated, naive), Open3D" >&2
  "$BIN/stereo_fusion_fuse" "$SEQ" "$out/ours" --set voxel_size_m="$v" --quiet >&2
  "$BIN/stereo_fusion_fuse" "$SEQ" "$out/naive" --set voxel_size_m="$v" --set lookup_mode=naive --quiet >&2
  # Beside a SLAM stack one core may be busy: the same run with a competing busy loop.
  ( while :; do :; done ) &
  busy_pid=$!
  "$BIN/stereo_fusion_fuse" "$SEQ" "$out/busy" --set voxel_size_m="$v" --quiet >&2 || true
  kill "$busy_pid" 2>/dev/null; wait "$busy_pid" 2>/dev/null || true
  /usr/bin/python3 "$ROOT/tools/bench/open3d_fuse.py" "$SEQ" "$out/open3d.ply" "$v" \
    "$(/usr/bin/python3 -c "print(4*$v)")" 8 10 > "$out/open3d.json"
  "$BIN/stereo_fusion_evaluate" "$out/ours/mesh.ply" "$SEQ" --tolerance-m "$tol" --json "$out/ours_eval.json" >/dev/null 2>&1
  "$BIN/stereo_fusion_evaluate" "$out/open3d.ply" "$SEQ" --tolerance-m "$tol" --json "$out/open3d_eval.json" >/dev/null 2>&1
done

echo
echo "stereo_fusion vs Open3D ScalableTSDFVolume — $FRAMES frames 640×480 SGBM $PRESET, $(nproc) cores, medians in ms"
printf "%-6s | %-13s | %7s %7s %7s %7s | %7s %7s %7s | %6s | %6s %6s | %8s %8s %6s\n" \
  voxel system "lookN" "lookA" fusion mesh "total" "mean" "p99" fps blocks MB "acc_mm" "compl%" F%
for row in "${rows[@]}"; do
  IFS='|' read -r v out tol <<<"$row"
  s="$out/ours/stats.json"; n="$out/naive/stats.json"; e="$out/ours_eval.json"; o="$out/open3d.json"; oe="$out/open3d_eval.json"
  printf "%-6s | %-13s | %7.1f %7.1f %7.1f %7.1f | %7.1f %7.1f %7.1f | %6.1f | %6d %6.1f | %8.2f %8.1f %6.1f\n" "$v" stereo_fusion \
    "$(json "$n" "d['timings_ms']['lookup']['p50']")" "$(json "$s" "d['timings_ms']['lookup']['p50']")" \
    "$(json "$s" "d['timings_ms']['fusion']['p50']")" "$(json "$s" "d['timings_ms']['meshing']['p50']")" \
    "$(json "$s" "d['timings_ms']['total']['p50']")" "$(json "$s" "d['timings_ms']['total']['mean']")" \
    "$(json "$s" "d['timings_ms']['total']['p99']")" \
    "$(json "$s" "1000.0/d['timings_ms']['total']['p50']")" "$(json "$s" "d['blocks']['total']")" \
    "$(json "$s" "d['memory']['megabytes']")" "$(json "$e" "d['accuracy_m']['median']*1000")" \
    "$(json "$e" "d['completeness']*100")" "$(json "$e" "d['f_score']*100")"
  printf "%-6s | %-13s | %7s %7s %7.1f %7s | %7.1f %7.1f %7.1f | %6.1f | %6s %6s | %8.2f %8.1f %6.1f\n" "$v" "Open3D (int.)" - - \
    "$(json "$o" "d['integrate_ms']['p50']")" "-" "$(json "$o" "d['integrate_ms']['p50']")" \
    "$(json "$o" "d['integrate_ms']['mean']")" "$(json "$o" "d['integrate_ms']['p99']")" \
    "$(json "$o" "1000.0/d['integrate_ms']['p50']")" - - \
    "$(json "$oe" "d['accuracy_m']['median']*1000")" "$(json "$oe" "d['completeness']*100")" \
    "$(json "$oe" "d['f_score']*100")"
  echo "       Open3D final mesh extraction: $(json "$o" "round(d['extract_ms'])") ms once; ours meshes incrementally every frame (in 'total')"
  echo "       Open3D with a mesh as current as ours (integrate + full extraction, p50 over every 10th frame): $(json "$o" "round(d['integrate_ms']['p50'] + d['live_extract_ms_p50'], 1)") ms per frame"
  echo "       frame-rate ratio ours / Open3D: $(/usr/bin/python3 -c "import json; s=json.load(open('$s')); o=json.load(open('$o')); t=s['timings_ms']['total']['p50']; print(f\"{o['integrate_ms']['p50']/t:.2f}x integration only, {(o['integrate_ms']['p50']+o['live_extract_ms_p50'])/t:.1f}x with a current mesh; our lookup+fusion alone vs their integration: {o['integrate_ms']['p50']/(s['timings_ms']['lookup']['p50']+s['timings_ms']['fusion']['p50']):.2f}x (p50), {o['integrate_ms']['mean']/(s['timings_ms']['lookup']['mean']+s['timings_ms']['fusion']['mean']):.2f}x (mean)\")")"
  if [ -f "$out/busy/stats.json" ]; then
    echo "       one core busy with another process: total p50 $(json "$out/busy/stats.json" "round(d['timings_ms']['total']['p50'], 1)") ms ($(/usr/bin/python3 -c "import json; b=json.load(open('$out/busy/stats.json')); s=json.load(open('$s')); print(round(b['timings_ms']['total']['p50']/s['timings_ms']['total']['p50'], 2))")× the run above)"
  fi
  echo "       work per frame (p50): $(json "$s" "'{:.0f} valid pixels, {:.0f} octree searches, {:.0f} blocks queued, {:.0f} updated ({:.0f} voxel updates), {:.0f} owners meshed, {:.0f} submeshes changed'.format(*[d['work_per_frame_p50'][k] for k in ('valid_points','octree_searches','blocks_queued','blocks_updated','voxels_updated','blocks_meshed','submeshes_changed')])")"
  echo "       voxel levels allocated: $(json "$s" "', '.join('{}³ in {} blocks ({:.1f} MB, {} B each)'.format(k, v['blocks'], v['bytes']/1048576, v['bytes_per_block']) for k, v in d['memory']['levels'].items())"); fixed part $(json "$s" "round(d['memory']['block_fixed_bytes']/max(1, d['blocks']['total']))") B per block; peak RSS $(json "$s" "round(d['memory']['peak_rss_megabytes'])") MB"
  echo "       memory: $(json "$s" "round(d['memory']['bytes_per_block'])") B per block incl. octree; a dense grid of 12-byte voxels over the same bounds: $(json "$s" "round(d['memory']['dense_grid_megabytes'])") MB ($(json "$s" "round(d['memory']['dense_grid_ratio'], 1)")× ours)"
done
echo "lookN / lookA: octree lookup with Algorithm 1 (naive) / Algorithm 2 (accelerated); tolerance for completeness: max(5 cm, 2 voxels)"
