# Shared by scripts/demo.sh, bandwidth.sh and screenshots.sh (sourced, not run): the ROS
# environment, the demo bag and a private ROS master. Expects ROOT and BUILD_DIR to be set.
# demo_bag, start_master and stop_pids are tools/demo/demo_session.sh's, which the installed demo
# (tools/demo/demo.sh) shares.
# shellcheck source=tools/demo/demo_session.sh
source "$ROOT/tools/demo/demo_session.sh"

# ROS tools run on Debian's Python (ros-on-debian.md #1); the built package goes on the paths.
ros_env() {
  export PYENV_VERSION=system ROS_HOSTNAME=localhost
  set +u
  # shellcheck disable=SC1091
  source "$BUILD_DIR/devel/setup.bash"
  set -u
}

# ensure_demo_bag FRAMES TAG: sets DEMO (the repository's .demo/) and BAG (demo_bag).
ensure_demo_bag() {
  DEMO="$ROOT/.demo"
  demo_bag "$BUILD_DIR/devel/lib/stereo_fusion/stereo_fusion_simulate" "$DEMO" "$1" "$2"
}
