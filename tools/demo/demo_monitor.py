#!/usr/bin/python3
"""Follows a running stereo_fusion: prints progress from /diagnostics once a second and, when
all expected frames are accounted for (fused + dropped) or nothing happened for --idle-s
seconds, the per-stage timing table. Exits with 1 at once if the --launch-pid process ends
first (roslaunch failed). Used by scripts/demo.sh and, with --subscribe, --unpause, --cpu-node and
--json, by scripts/bench_live.sh: it then also subscribes to the node's outputs as rviz, a
planner or a base station would, starts a paused player, and measures the node's CPU."""
import argparse
import json
import os
import sys
import time
import xmlrpc.client

import rosgraph
import rospy
from diagnostic_msgs.msg import DiagnosticArray
from std_srvs.srv import SetBool

values = {}


def on_diagnostics(msg):
    for status in msg.status:
        if "fusion" in status.name:
            values.update({kv.key: kv.value for kv in status.values})


def number(key, default=0.0):
    try:
        return float(values.get(key, default))
    except ValueError:
        return default


def missed_upstream():
    """Measurements lost before the node (header.seq gaps): disparities, or depth images with
    input: depth (the key names what the input takes)."""
    return sum(number(f"{m} missed upstream (header.seq gaps)") for m in ("disparities", "depth images"))


def dropped_keys():
    return sorted(k for k in list(values) if k.startswith("dropped: "))


def node_pid(name):
    """The process id of a running ROS node, from its own API (0 if it cannot be reached)."""
    try:
        uri = rosgraph.Master(rospy.get_name()).lookupNode(name)
        code, _, pid = xmlrpc.client.ServerProxy(uri).getPid(rospy.get_name())
        return int(pid) if code == 1 else 0
    except Exception:  # not up yet, or gone
        return 0


def cpu_seconds(pid):
    """User + system CPU seconds of a process and all its threads so far."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, IndexError, ValueError):
        return float("nan")


def alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--frames", type=int, required=True, help="frames the bag holds")
    parser.add_argument("--idle-s", type=float, default=30.0)
    parser.add_argument("--launch-pid", type=int, default=0, help="stop as soon as this process ends")
    parser.add_argument("--subscribe", nargs="*", default=[], help="topics to subscribe to (any type)")
    parser.add_argument("--unpause", default="", help="std_srvs/SetBool service that starts a paused player")
    parser.add_argument("--cpu-node", nargs="*", default=[], help="nodes whose processes' CPU time to measure")
    parser.add_argument("--json", default="", help="also write the figures to this file")
    args = parser.parse_args(rospy.myargv()[1:])
    rospy.init_node("stereo_fusion_demo_monitor", anonymous=True, disable_signals=True)
    rospy.Subscriber("/diagnostics", DiagnosticArray, on_diagnostics)
    received = {topic: 0 for topic in args.subscribe}

    def counter(topic):
        def on_message(_):
            received[topic] += 1
        return on_message

    subscribers = [rospy.Subscriber(t, rospy.AnyMsg, counter(t), queue_size=10) for t in args.subscribe]
    pids = {}
    for node in args.cpu_node:
        for _ in range(300):
            pids[node] = node_pid(node)
            if pids[node]:
                break
            time.sleep(0.1)
    cpu_start, wall_start = {n: cpu_seconds(p) for n, p in pids.items() if p}, time.time()
    if args.unpause:
        rospy.wait_for_service(args.unpause, timeout=60)
        # Subscribers connect asynchronously: give the node's publishers time to see them.
        for _ in range(100):
            if all(s.get_num_connections() > 0 for s in subscribers):
                break
            time.sleep(0.1)
        time.sleep(1.0)
        cpu_start, wall_start = {n: cpu_seconds(p) for n, p in pids.items()}, time.time()
        rospy.ServiceProxy(args.unpause, SetBool)(False)
    last, last_change = -1, time.time()
    cpu_last = {}  # the last reading of each process: a player that ends keeps its total
    while True:
        time.sleep(1.0)
        for n, p in pids.items():
            seconds = cpu_seconds(p) if p else float("nan")
            if seconds == seconds:
                cpu_last[n] = (seconds, time.time())
        if args.launch_pid and not alive(args.launch_pid):
            print("[demo] roslaunch ended before the frames were fused", flush=True)
            return 1
        fused = int(number("frames fused"))
        # lost before the node (header.seq gaps) or dropped in it
        dropped = int(missed_upstream() + sum(number(k) for k in dropped_keys()))
        print(f"[demo] {fused + dropped}/{args.frames} frames: {fused} fused, {dropped} dropped | "
              f"last {number('total p50 (ms)'):.1f} ms/frame (p50) | {int(number('blocks'))} blocks, "
              f"{number('memory (MB)'):.1f} MB", flush=True)
        if fused + dropped >= args.frames:
            break
        if fused + dropped != last:
            last, last_change = fused + dropped, time.time()
        elif time.time() - last_change > args.idle_s:
            print(f"[demo] no progress for {args.idle_s:.0f} s, stopping", flush=True)
            break
    # Cores used over the replay (from the unpause; from the monitor's start without one).
    cpu_cores = {n: (seconds - cpu_start.get(n, 0.0)) / (at - wall_start)
                 for n, (seconds, at) in cpu_last.items()}
    print()
    print("per-stage timings (ms): lookup, fusion and total per fused frame; meshing and texture per "
          f"meshing pass ({int(number('meshing passes'))} passes, at most mesh_publish_rate_hz)")
    print(f"{'stage':<10} {'p50':>8} {'p99':>8}")
    for stage in ("lookup", "fusion", "meshing", "texture", "total"):
        print(f"{stage:<10} {number(stage + ' p50 (ms)'):8.1f} {number(stage + ' p99 (ms)'):8.1f}")
    print(f"worker per frame (the frame period bounds it): p50 {number('worker per frame p50 (ms)'):.1f} ms, "
          f"p99 {number('worker per frame p99 (ms)'):.1f} ms; of it publishing p50 "
          f"{number('publishing per frame p50 (ms)'):.1f} ms, p99 {number('publishing per frame p99 (ms)'):.1f} ms")
    if number("planning updates") > 0:
        print(f"planning updates (distance field, beside the frames): {int(number('planning updates'))}, "
              f"p50 {number('planning update p50 (ms)'):.1f} ms, p99 {number('planning update p99 (ms)'):.1f} ms")
    print(f"latency stamp -> publish: p50 {number('latency p50 (s)') * 1000:.0f} ms, "
          f"p99 {number('latency p99 (s)') * 1000:.0f} ms")
    for k in dropped_keys():
        if number(k) > 0:
            print(f"{k}: {int(number(k))}")
    for node, cores in cpu_cores.items():
        print(f"CPU of {node} (pid {pids[node]}): {cores:.2f} cores over the replay")
    for topic, n in received.items():
        print(f"received {n} messages on {topic}")
    if args.json:
        figures = {"frames_fused": int(number("frames fused")),
                   "frames_missed_upstream": int(missed_upstream()),
                   "frames_dropped": {k[len("dropped: "):]: int(number(k)) for k in dropped_keys()},
                   "latency_p50_s": number("latency p50 (s)"), "latency_p99_s": number("latency p99 (s)"),
                   "stage_ms": {s: {"p50": number(s + " p50 (ms)"), "p99": number(s + " p99 (ms)")}
                                for s in ("lookup", "fusion", "meshing", "texture", "total")},
                   "meshing_passes": int(number("meshing passes")),
                   "worker_ms": {"p50": number("worker per frame p50 (ms)"), "p99": number("worker per frame p99 (ms)")},
                   "publishing_ms": {"p50": number("publishing per frame p50 (ms)"),
                                     "p99": number("publishing per frame p99 (ms)")},
                   "planning_update_ms": {"updates": int(number("planning updates")),
                                          "p50": number("planning update p50 (ms)"),
                                          "p99": number("planning update p99 (ms)")},
                   "cpu_cores": cpu_cores, "messages_received": received}
        with open(args.json, "w") as f:
            json.dump(figures, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
