#!/usr/bin/env bash
# Source me: puts the built package on the ROS paths so roslaunch / rosrun find stereo_fusion.
#   source scripts/env.sh
_sf_root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if [ ! -f "${BUILD_DIR:-$_sf_root/.build}/devel/setup.bash" ]; then
  echo "stereo_fusion: not built yet, run scripts/setup.sh first" >&2
  return 1 2>/dev/null || exit 1
fi
export PYENV_VERSION=system
export ROS_HOSTNAME="${ROS_HOSTNAME:-localhost}"
_sf_nounset=0
case $- in *u*) _sf_nounset=1; set +u ;; esac
# shellcheck disable=SC1091
source "${BUILD_DIR:-$_sf_root/.build}/devel/setup.bash"
[ "$_sf_nounset" = 1 ] && set -u
unset _sf_root _sf_nounset
