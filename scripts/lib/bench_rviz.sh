# shellcheck shell=bash
# A real rviz for scripts/bench_live.sh (sourced, not run): on a virtual X screen of its own
# (xvfb-run -a, Mesa's software OpenGL), showing the mesh alone, through the display
# stereo_fusion/Mesh or through the markers. Expects ROOT, a ROS environment and the private
# master (ROS_MASTER_URI) to be set.
BENCH_RVIZ_XVFB_PID=""
BENCH_RVIZ_NODE=/bench_rviz  # its node name (__name:=), so the monitor can measure its CPU

# bench_rviz_config MODE OUT: rviz/stereo_fusion.rviz with only the mesh ticked, through the
# plugin (MODE plugin: *Mesh*) or the markers (MODE markers: *Mesh (markers)*); the other
# displays (camera path and frustum, grid, ESDF slice, tf) off so that rviz's work is the mesh's.
bench_rviz_config() {
  local mode="$1" out="$2" plugin=true markers=false
  if [ "$mode" = markers ]; then plugin=false markers=true; fi
  sed -E -e '/Name: (Camera path|Camera frustum|Occupancy grid|ESDF slice|TF)$/{n;s/Enabled: true/Enabled: false/}' \
    -e "/Name: Mesh\$/{n;s/Enabled: (true|false)/Enabled: $plugin/}" \
    -e "/Name: Mesh \\(markers\\)\$/{n;s/Enabled: (true|false)/Enabled: $markers/}" \
    "$ROOT/rviz/stereo_fusion.rviz" >"$out"
  # The displays are found by name: a renamed one would leave both routes on, or neither.
  local on
  on="$(grep -A1 -E 'Name: Mesh( \(markers\))?$' "$out" | grep -c 'Enabled: true' || true)"
  if [ "$on" != 1 ]; then
    echo "[live] $out shows the mesh through $on displays, not 1: has rviz/stereo_fusion.rviz changed?" >&2
    exit 1
  fi
}

# bench_rviz_wait WHAT TIMEOUT_S PYTHON_CONDITION WATCH_PID: polls the master until the condition
# (on `pubs` and `subs`, {topic: [nodes]}) holds; exits the script after TIMEOUT_S or as soon as
# the process WATCH_PID ended.
bench_rviz_wait() {
  local what="$1" timeout_s="$2" condition="$3" watch_pid="$4"
  if ! /usr/bin/python3 - "$timeout_s" "$condition" "$watch_pid" <<'PY'; then
import os, sys, time, rosgraph
timeout_s, condition, watch_pid = float(sys.argv[1]), sys.argv[2], int(sys.argv[3])
end = time.monotonic() + timeout_s
while time.monotonic() < end:
    try:
        os.kill(watch_pid, 0)
    except ProcessLookupError:
        sys.exit(1)
    try:
        p, s, _ = rosgraph.Master("/bench_rviz_wait").getSystemState()
        pubs, subs = dict(p), dict(s)
        if eval(condition):
            sys.exit(0)
    except (OSError, rosgraph.MasterException):
        pass
    time.sleep(0.5)
sys.exit(1)
PY
    echo "[live] $what within $timeout_s s (or its process ended)" >&2
    exit 1
  fi
}

# start_bench_rviz MODE MESH_TOPIC LOG_PREFIX LAUNCH_PID: writes LOG_PREFIX_MODE.rviz, starts rviz
# once the node advertises MESH_TOPIC and returns when rviz subscribed to it.
start_bench_rviz() {
  local mode="$1" topic="$2" prefix="$3" launch_pid="$4" config
  config="${prefix}_$mode.rviz"
  BENCH_RVIZ_LOG="${prefix}_$mode.log"
  bench_rviz_config "$mode" "$config"
  bench_rviz_wait "the node did not advertise $topic (see the launch log)" 120 "'$topic' in pubs" "$launch_pid"
  echo "[live] rviz on a virtual screen, the mesh through the $mode (config $config, log $BENCH_RVIZ_LOG)"
  LIBGL_ALWAYS_SOFTWARE=1 xvfb-run -a -s "-screen 0 1280x800x24" \
    rviz -d "$config" "__name:=${BENCH_RVIZ_NODE#/}" >"$BENCH_RVIZ_LOG" 2>&1 &
  BENCH_RVIZ_XVFB_PID=$!
  bench_rviz_wait "rviz did not subscribe to $topic (see $BENCH_RVIZ_LOG)" 120 "'$BENCH_RVIZ_NODE' in subs.get('$topic', [])" \
    "$BENCH_RVIZ_XVFB_PID"
  if ! kill -0 "$BENCH_RVIZ_XVFB_PID" 2>/dev/null || ! kill -0 "$launch_pid" 2>/dev/null; then
    echo "[live] rviz or the replay ended before the start; see $BENCH_RVIZ_LOG" >&2
    exit 1
  fi
  if grep -E "could not be loaded|Failed to load library" "$BENCH_RVIZ_LOG" >&2; then exit 1; fi
}

# stop_bench_rviz: SIGINT to rviz (xvfb-run's child, started above), which xvfb-run follows by
# stopping its X server; SIGKILL after BENCH_RVIZ_STOP_S (90 s: on a loaded machine rviz can
# take tens of seconds to work off its queue of marker arrays and free their objects). Says how
# rviz ended and how long it took. Safe to call twice.
BENCH_RVIZ_STOP_S="${BENCH_RVIZ_STOP_S:-90}"
stop_bench_rviz() {
  [ -n "$BENCH_RVIZ_XVFB_PID" ] || return 0
  local xvfb_pid="$BENCH_RVIZ_XVFB_PID" rviz_pid code=0 start_s=$SECONDS
  BENCH_RVIZ_XVFB_PID=""
  rviz_pid="$(pgrep -P "$xvfb_pid" -x rviz || true)"
  if [ -n "$rviz_pid" ]; then kill -INT "$rviz_pid" 2>/dev/null || true; fi
  while kill -0 "$xvfb_pid" 2>/dev/null && ((SECONDS - start_s < BENCH_RVIZ_STOP_S)); do sleep 0.5; done
  if kill -0 "$xvfb_pid" 2>/dev/null; then
    echo "[live] rviz did not end within $BENCH_RVIZ_STOP_S s of SIGINT: killed" >&2
    if [ -n "$rviz_pid" ]; then kill -KILL "$rviz_pid" 2>/dev/null || true; fi
  fi
  wait "$xvfb_pid" 2>/dev/null || code=$?
  echo "[live] rviz stopped (exit code $code, $((SECONDS - start_s)) s after SIGINT)"
}
