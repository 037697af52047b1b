#!/usr/bin/env bash
# Offline reconstruction without a ROS master:
#   scripts/fuse.sh <seq-folder | file.bag> <out-dir> [--config FILE] [--set key=value ...] [--frames N] [--mesh-every N]
#                   [--trajectory FILE]
# Writes <out-dir>/mesh.ply (vertex colours) and <out-dir>/stats.json. Installs and builds first.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$ROOT/scripts/setup.sh" --targets stereo_fusion_fuse >&2
exec "${BUILD_DIR:-$ROOT/.build}/devel/lib/stereo_fusion/stereo_fusion_fuse" "$@"
