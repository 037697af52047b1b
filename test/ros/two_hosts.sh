#!/usr/bin/env bash
# The robot and the base station on two "hosts": two network namespaces made here and joined
# only by a veth pair (10.213.50.1/30 robot, .2/30 base station; no route leaves them, so
# nothing else on any network is ever a target). Robot: roscore on a free port, the fusion
# nodelet replaying BAG (replay.launch). Base station: ROS_MASTER_URI on the robot's master,
# base_station.launch's mesh assembler and CHECKER (test_two_hosts.cpp), which checks that the
# assembled mesh equals the robot's. Each side sources scripts/env.sh with ROS_IP set to its
# own address and ROS_HOSTNAME unset (it would win over ROS_IP), as doc/ros_interface.md
# #two-machines tells users to.
#   test/ros/two_hosts.sh BUILD_DIR BAG CHECKER
# Exits 0 passed, 1 failed, 77 skipped (ctest's SKIP_RETURN_CODE) with a line "SKIP: <why>"
# where network namespaces cannot be made (not root: no CAP_SYS_ADMIN / CAP_NET_ADMIN; no veth).
set -uo pipefail
if [ $# -ne 3 ]; then
  echo "usage: $0 BUILD_DIR BAG CHECKER" >&2
  exit 2
fi
build_dir=$1 bag=$2 checker=$3
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
readonly skip_code=77
# The process id and a random number: parallel runs never share a namespace's name. The
# addresses can be the same in every run: each pair exists only inside its own namespaces.
run_id="$$_${RANDOM}"
robot_ns="sf2h_robot_$run_id" base_ns="sf2h_base_$run_id"
robot_ip=10.213.50.1 base_ip=10.213.50.2
work="$(mktemp -d /tmp/stereo_fusion_two_hosts.XXXXXX)"
pids=()
made_ns=()

# Every exit (pass, failure, interrupt): stop what was started, then the namespaces go with
# their veth pair. SIGTERM first, so roslaunch stops its nodes (SIGINT would not do: background
# jobs of a script start with it ignored), then SIGKILL whatever still runs in the two
# namespaces (only this run's processes are in them).
cleanup() {
  local status=$? pid ns
  trap - EXIT INT TERM HUP
  for pid in "${pids[@]}"; do kill -TERM "$pid" 2>/dev/null; done
  for _ in $(seq 1 100); do
    local alive=0
    for pid in "${pids[@]}"; do kill -0 "$pid" 2>/dev/null && alive=1; done
    [ "$alive" = 0 ] && break
    sleep 0.2
  done
  for ns in "${made_ns[@]}"; do
    for pid in $(ip netns pids "$ns" 2>/dev/null); do kill -KILL "$pid" 2>/dev/null; done
  done
  for ns in "${made_ns[@]}"; do ip netns delete "$ns" || status=1; done
  if [ "$status" -ne 0 ] && [ "$status" -ne "$skip_code" ]; then
    for log in "$work"/roscore.log "$work"/robot.log "$work"/base_station.log; do
      [ -f "$log" ] && { echo "--- $(basename "$log") (last 40 lines)"; tail -n 40 "$log"; }
    done
  fi
  rm -rf "$work"
  exit "$status"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM
trap 'exit 129' HUP

skip() {
  echo "SKIP: two_hosts: $*"
  exit "$skip_code"
}
fail() {
  echo "FAIL: two_hosts: $*"
  exit 1
}

command -v ip >/dev/null || skip "iproute2's ip is not installed"
err="$(ip netns add "$robot_ns" 2>&1)" ||
  skip "cannot create a network namespace ($err): needs root (CAP_SYS_ADMIN and CAP_NET_ADMIN)"
made_ns+=("$robot_ns")
err="$(ip netns add "$base_ns" 2>&1)" || fail "second namespace: $err"
made_ns+=("$base_ns")
# Both ends made inside the namespaces: the pair never appears on this machine's own network.
err="$(ip -n "$robot_ns" link add sf_robot type veth peer name sf_base netns "$base_ns" 2>&1)" ||
  skip "cannot create a veth pair ($err)"
ip -n "$robot_ns" addr add "$robot_ip/30" dev sf_robot || fail "address on the robot's end"
ip -n "$base_ns" addr add "$base_ip/30" dev sf_base || fail "address on the base station's end"
# lo too: Linux delivers traffic to a host's own address through it, and each side's nodes talk
# to each other at their own ROS_IP (a nodelet manager and its loader, rosout).
for link in "$robot_ns lo" "$robot_ns sf_robot" "$base_ns lo" "$base_ns sf_base"; do
  read -r ns dev <<<"$link"
  ip -n "$ns" link set dev "$dev" up || fail "cannot set $dev up in $ns"
done

# A free port for the master, chosen inside the robot's namespace (nothing else runs there).
port="$(ip netns exec "$robot_ns" /usr/bin/python3 -c \
  'import socket, sys; s = socket.socket(); s.bind((sys.argv[1], 0)); print(s.getsockname()[1])' \
  "$robot_ip")" || fail "no free port in the robot's namespace"
master="http://$robot_ip:$port"

# NS IP NAME CMD...: CMD in namespace NS as that host's user would start it (ROS_IP=IP,
# ROS_MASTER_URI on the robot, scripts/env.sh sourced), in the background, output to NAME.log.
start_in() {
  local ns=$1 ip=$2 name=$3
  shift 3
  ip netns exec "$ns" env -u ROS_HOSTNAME ROS_IP="$ip" ROS_MASTER_URI="$master" \
    ROS_HOME="$work/$name" BUILD_DIR="$build_dir" \
    bash -c 'source "$0/scripts/env.sh" && exec "$@"' "$root" "$@" >"$work/$name.log" 2>&1 &
  pids+=($!)
}

start_in "$robot_ns" "$robot_ip" roscore roscore -p "$port"
online=0
deadline=$((SECONDS + 60))
while [ "$SECONDS" -lt "$deadline" ]; do
  if ip netns exec "$robot_ns" env ROS_MASTER_URI="$master" /usr/bin/python3 -c \
    'import rosgraph, sys; sys.exit(0 if rosgraph.is_master_online() else 1)' 2>/dev/null; then
    online=1
    break
  fi
  kill -0 "${pids[0]}" 2>/dev/null || break
  sleep 0.2
done
[ "$online" = 1 ] || fail "the robot's master did not come up at $master"

# The robot: the bag waits paused for the checker (test::startPausedPlayer) and for the
# nodelet's subscriptions, so every frame is fused.
start_in "$robot_ns" "$robot_ip" robot roslaunch stereo_fusion replay.launch bag:="$bag" \
  config:="$root/test/ros/test_config.yaml" player_required:=false wait_for_subscribers:=true \
  start_paused:=true
# The base station, as a user starts it there (no rviz in a test).
start_in "$base_ns" "$base_ip" base_station roslaunch stereo_fusion base_station.launch rviz:=false
# Its waits add up to more than ctest's TIMEOUT (360 s), whose SIGKILL no trap sees: bounded here.
start_in "$base_ns" "$base_ip" checker timeout -k 10 240 "$checker" _bag:="$bag" \
  _robot_ip:="$robot_ip" _base_ip:="$base_ip"
checker_pid=${pids[-1]}
# wait, not a foreground run: an INT or TERM then reaches the trap at once.
wait "$checker_pid"
status=$?
cat "$work/checker.log"
[ "$status" -eq 0 ] || fail "the base station's check failed (exit $status)"
echo "two_hosts: the base station ($base_ip) assembled exactly the robot's ($robot_ip) mesh"
