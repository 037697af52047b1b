#!/usr/bin/env bash
# Scores a reconstructed mesh. Installs what is missing and builds (scripts/setup.sh), then runs
# the evaluator:
#   scripts/evaluate.sh <mesh.ply> <gt_mesh.ply | seq-folder> [--tolerance-m 0.04] [--json out.json]
#                       [--held-out odd|even|i,j,k] [--samples N] [--seed K] [--error-ply F]
#                       [--missing-ply F]
# With a ground-truth .ply: accuracy, completeness, precision, F-score. With a sequence folder
# holding gt_mesh.ply: the same, completeness over the ground truth the frames saw. With a
# sequence folder without ground truth: the mesh rendered into held-out frames and compared
# with their measured depth. --error-ply (ground truth only) also writes the mesh coloured by
# each vertex's error, --missing-ply the evaluated ground-truth samples coloured by their
# distance to the mesh (where it is incomplete). `scripts/evaluate.sh --help` lists every option.
# Exit codes: 0 ok, 1 unreadable input (or setup/build failure), 2 bad arguments.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/.build}"

# Setup's progress goes to stderr so that stdout carries only the evaluator's table.
if ! "$ROOT/scripts/setup.sh" --targets stereo_fusion_evaluate >&2; then
  echo "setup or build failed" >&2
  exit 1
fi
export PYENV_VERSION=system
exec "$BUILD_DIR/devel/lib/stereo_fusion/stereo_fusion_evaluate" "$@"
