#!/usr/bin/env bash
# Renders a simulated stereo sequence (analytic room or tabletop scene) into a dataset folder:
# calibration.yaml, poses.txt, disparity/ color/ right/ NNNNNN.png and gt_mesh.ply.
# Installs what is missing and builds first (quiet unless that fails).
#   scripts/simulate.sh --out DIR [--preset room|tabletop|hall] [--trajectory orbit|walkthrough]
#                       [--frames N] [--disparity exact|noisy|sgbm] [--seed K] ...   (--help: all)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/.build}"

log="$(mktemp)"
if ! "$ROOT/scripts/setup.sh" --targets stereo_fusion_simulate >"$log" 2>&1; then
  cat "$log" >&2
  rm -f "$log"
  echo "simulate: setup or build failed" >&2
  exit 1
fi
rm -f "$log"

exec "$BUILD_DIR/devel/lib/stereo_fusion/stereo_fusion_simulate" "$@"
