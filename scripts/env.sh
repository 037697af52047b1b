#!/usr/bin/env bash
# Source me: puts the built package on the ROS paths so roslaunch / rosrun find stereo_fusion.
#   source scripts/env.sh
_sf_root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if [ ! -f "${BUILD_DIR:-$_sf_root/.build}/devel/setup.bash" ]; then
  echo "stereo_fusion: not built yet, run scripts/setup.sh first" >&2
  return 1 2>/dev/null || exit 1
fi
export PYENV_VERSION=system
# Which address this machine's nodes advertise. A master on this machine (ROS_MASTER_URI unset or
# on localhost / 127.x / ::1) with neither ROS_HOSTNAME nor ROS_IP set: localhost, which resolves
# in any container. Otherwise it is left alone: a robot and a base station on two hosts must
# each advertise an address the other can reach (ROS_IP, or a ROS_HOSTNAME the other resolves;
# doc/ros_interface.md#two-machines), and localhost would send the other side to itself.
if [ -z "${ROS_HOSTNAME:-}" ] && [ -z "${ROS_IP:-}" ]; then
  _sf_master="${ROS_MASTER_URI:-http://localhost:11311}"
  _sf_master="${_sf_master#*://}"
  _sf_master="${_sf_master%%/*}"
  case "$_sf_master" in
    \[*) _sf_master="${_sf_master%%]*}]" ;;  # [IPv6]:port
    *) _sf_master="${_sf_master%:*}" ;;
  esac
  case "$_sf_master" in
    localhost | 127.* | "[::1]" | ::1) export ROS_HOSTNAME=localhost ;;
    *)
      echo "stereo_fusion: ROS_MASTER_URI is on $_sf_master; set ROS_IP (or ROS_HOSTNAME) to an" \
        "address of this machine that $_sf_master can reach (doc/ros_interface.md#two-machines)" >&2
      ;;
  esac
  unset _sf_master
fi
_sf_nounset=0
case $- in *u*) _sf_nounset=1; set +u ;; esac
# shellcheck disable=SC1091
source "${BUILD_DIR:-$_sf_root/.build}/devel/setup.bash"
[ "$_sf_nounset" = 1 ] && set -u
unset _sf_root _sf_nounset
