#!/usr/bin/env bash
# The main job on the built-in default sequence: installs what is missing, builds, generates
# the simulated room bag on first use, starts a ROS master on a free port, replays the bag
# through the nodelet (launch/replay.launch), prints progress and the per-stage timing table,
# saves demo_output/mesh.ply and stops everything it started.
#   scripts/demo.sh [--rviz] [--frames N] [--rate R]
# The run itself is tools/demo/demo.sh, which an installed package runs too (rosrun stereo_fusion demo.sh).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/.build}"
RVIZ=false
ARGS=()
while [ $# -gt 0 ]; do
  case "$1" in
    --rviz) RVIZ=true; ARGS+=("$1"); shift ;;
    --frames | --rate) ARGS+=("$1" "$2"); shift 2 ;;
    -h|--help) sed -n '2,7p' "$0"; exit 0 ;;
    *) echo "demo.sh: unknown option $1" >&2; exit 2 ;;
  esac
done

"$ROOT/scripts/setup.sh" --targets "stereo_fusion_nodelet stereo_fusion_simulate stereo_fusion_generate_messages"
if [ "$RVIZ" = true ] && ! command -v rviz >/dev/null; then
  echo "[demo] installing rviz" >&2
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends rviz >/dev/null
fi
# shellcheck source=scripts/lib/ros_session.sh
source "$ROOT/scripts/lib/ros_session.sh"
ros_env
exec "$ROOT/tools/demo/demo.sh" --work-dir "$ROOT/.demo" --output-dir "$ROOT/demo_output" "${ARGS[@]}"
