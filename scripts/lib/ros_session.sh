# Shared by scripts/demo.sh, bandwidth.sh and screenshots.sh (sourced, not run): the ROS
# environment, the demo bag and a private ROS master. Expects ROOT and BUILD_DIR to be set.

# ROS tools run on Debian's Python (ros-on-debian.md #1); the built package goes on the paths.
ros_env() {
  export PYENV_VERSION=system ROS_HOSTNAME=localhost
  set +u
  # shellcheck disable=SC1091
  source "$BUILD_DIR/devel/setup.bash"
  set -u
}

# ensure_demo_bag FRAMES TAG: sets DEMO and BAG, simulating the room sequence (640×480, SGBM,
# walkthrough, seed 1) as a rosbag on first use. The name carries the bag's tf frame (map, the
# nodelet's default world_frame): a bag cached before that default changed from world has
# another name and is not replayed into a node that would find no transform for any frame.
ensure_demo_bag() {
  local frames="$1" tag="$2"
  DEMO="$ROOT/.demo"
  BAG="$DEMO/room_${frames}_map.bag"
  mkdir -p "$DEMO"
  if [ ! -f "$BAG" ]; then
    echo "[$tag] generating the simulated room ($frames frames, 640x480, SGBM) -> $BAG"
    "$BUILD_DIR/devel/lib/stereo_fusion/stereo_fusion_simulate" --preset room --trajectory walkthrough \
      --frames "$frames" --disparity sgbm --seed 1 --out "$DEMO/room_${frames}" --bag "$BAG.part"
    mv "$BAG.part" "$BAG"
  fi
}

# start_master TAG LOG: a ROS master on a free port (never a fixed one: parallel runs clash),
# exported as ROS_MASTER_URI; its PID is appended to the caller's PIDS array. Waits until it is up.
start_master() {
  local tag="$1" log="$2" port
  # roscore and roslaunch find their own machine by the name localhost.
  if ! getent hosts localhost >/dev/null; then
    echo "[$tag] the name localhost does not resolve (ROS needs it): add '127.0.0.1 localhost' to /etc/hosts" >&2
    exit 1
  fi
  port="$(/usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("", 0)); print(s.getsockname()[1])')"
  export ROS_MASTER_URI="http://localhost:$port"
  echo "[$tag] ROS master on port $port"
  roscore -p "$port" >"$log" 2>&1 &
  PIDS+=($!)
  /usr/bin/python3 -c '
import sys, time, rosgraph
for _ in range(100):
    if rosgraph.is_master_online():
        sys.exit(0)
    time.sleep(0.1)
sys.exit(sys.argv[1])' "[$tag] the ROS master did not come up, see $log"
}

# stop_pids: SIGINT to everything in PIDS (roslaunch shuts its nodes down), then SIGKILL.
stop_pids() {
  for pid in "${PIDS[@]}"; do kill -INT "$pid" 2>/dev/null || true; done
  sleep 1
  for pid in "${PIDS[@]}"; do kill -KILL "$pid" 2>/dev/null || true; wait "$pid" 2>/dev/null || true; done
  PIDS=()
}
