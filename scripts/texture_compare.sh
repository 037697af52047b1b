#!/usr/bin/env bash
# Textured vs vertex-coloured mesh against ground truth (doc/offline_tools.md, "Texture comparison").
#   scripts/texture_compare.sh [--frames N] [--views K] [--out DIR] [extra stereo_fusion_texture_compare args]
# Simulates the SGBM room sequence once (.texture_compare/room_N, cached), fuses its even frames
# with texture=patches, renders both meshes into the odd (held-out) frames' poses, prints PSNR and
# gradient energy of both against the simulator's exact images, and writes the figures
# (default: doc/images/texture_compare_{full,zoom}.png) and texture_compare.json.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/.build}"
FRAMES=60
VIEWS=10
OUT="$ROOT/doc/images"
EXTRA=()
while (($#)); do
  case "$1" in
    --frames) FRAMES="$2"; shift 2 ;;
    --views) VIEWS="$2"; shift 2 ;;
    --out) OUT="$2"; shift 2 ;;
    *) EXTRA+=("$1"); shift ;;
  esac
done

log="$(mktemp)"
if ! "$ROOT/scripts/setup.sh" >"$log" 2>&1; then
  cat "$log" >&2
  rm -f "$log"
  echo "texture_compare: setup or build failed" >&2
  exit 1
fi
rm -f "$log"

# A path relative to the repository, so the committed texture_compare.json names no machine path.
mkdir -p "$OUT"
OUT="$(cd "$OUT" && pwd)"  # before the cd below: --out is relative to the caller's directory
cd "$ROOT"
SEQ=".texture_compare/room_$FRAMES"
if [ ! -f "$SEQ/poses.txt" ]; then
  echo "[texture_compare] simulating the room sequence ($FRAMES frames, SGBM) into $SEQ"
  "$BUILD_DIR/devel/lib/stereo_fusion/stereo_fusion_simulate" --preset room --frames "$FRAMES" \
    --disparity sgbm --out "$SEQ" >/dev/null
fi
mkdir -p "$OUT"
"$BUILD_DIR/devel/lib/stereo_fusion/stereo_fusion_texture_compare" "$SEQ" "$OUT" --views "$VIEWS" "${EXTRA[@]}"
echo "[texture_compare] wrote $OUT/texture_compare_full.png, texture_compare_zoom.png, texture_compare.json"

# Optional third-party check of the export (python3-open3d is not a dependency of the package).
if /usr/bin/python3 -c "import open3d" >/dev/null 2>&1; then
  tmp="$(mktemp -d)"
  "$BUILD_DIR/devel/lib/stereo_fusion/stereo_fusion_fuse" "$SEQ" "$tmp" --set texture=patches --quiet >/dev/null
  /usr/bin/python3 - "$tmp/mesh.obj" <<'PY'
import sys
import numpy as np
import open3d as o3d
m = o3d.io.read_triangle_mesh(sys.argv[1], True)
textures = [np.asarray(t).shape for t in m.textures if not t.is_empty()]
print(f"[texture_compare] Open3D {o3d.__version__} reads mesh.obj: {len(m.triangles)} triangles, "
      f"triangle UVs: {m.has_triangle_uvs()}, textures: {textures}")
PY
  rm -rf "$tmp"
fi
