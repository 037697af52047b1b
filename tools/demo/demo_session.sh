# shellcheck shell=bash
# Sourced (not run) by tools/demo/demo.sh and scripts/lib/ros_session.sh, in the source tree and
# installed beside demo.sh: the simulated demo bag, a private ROS master, stopping what was started.

# demo_bag SIMULATOR DIR FRAMES TAG: sets BAG, simulating the room sequence (640×480, SGBM,
# walkthrough, seed 1) into DIR as a rosbag on first use. The name carries the bag's tf frame (map,
# the nodelet's default world_frame): a bag cached before that default changed from world has
# another name and is not replayed into a node that would find no transform for any frame.
demo_bag() {
  local simulator="$1" dir="$2" frames="$3" tag="$4"
  BAG="$dir/room_${frames}_map.bag"
  mkdir -p "$dir"
  if [ ! -f "$BAG" ]; then
    echo "[$tag] generating the simulated room ($frames frames, 640x480, SGBM) -> $BAG"
    "$simulator" --preset room --trajectory walkthrough --frames "$frames" --disparity sgbm --seed 1 \
      --out "$dir/room_${frames}" --bag "$BAG.part"
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
