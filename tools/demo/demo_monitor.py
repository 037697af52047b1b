#!/usr/bin/python3
"""Follows a running stereo_fusion: prints progress from /diagnostics once a second and, when
all expected frames are accounted for (fused + dropped) or nothing happened for --idle-s
seconds, the per-stage timing table. Exits with 1 at once if the --launch-pid process ends
first (roslaunch failed). Used by scripts/demo.sh."""
import argparse
import os
import sys
import time

import rospy
from diagnostic_msgs.msg import DiagnosticArray

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


def dropped_keys():
    return sorted(k for k in list(values) if k.startswith("dropped: "))


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
    args = parser.parse_args(rospy.myargv()[1:])
    rospy.init_node("stereo_fusion_demo_monitor", anonymous=True, disable_signals=True)
    rospy.Subscriber("/diagnostics", DiagnosticArray, on_diagnostics)
    last, last_change = -1, time.time()
    while True:
        time.sleep(1.0)
        if args.launch_pid and not alive(args.launch_pid):
            print("[demo] roslaunch ended before the frames were fused", flush=True)
            return 1
        fused = int(number("frames fused"))
        # lost before the node (header.seq gaps) or dropped in it
        dropped = int(number("disparities missed upstream (header.seq gaps)") + sum(number(k) for k in dropped_keys()))
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
    print()
    print("per-stage timings (ms): lookup, fusion and total per fused frame; meshing and texture per "
          f"meshing pass ({int(number('meshing passes'))} passes, at most mesh_publish_rate_hz)")
    print(f"{'stage':<10} {'p50':>8} {'p99':>8}")
    for stage in ("lookup", "fusion", "meshing", "texture", "total"):
        print(f"{stage:<10} {number(stage + ' p50 (ms)'):8.1f} {number(stage + ' p99 (ms)'):8.1f}")
    print(f"latency stamp -> publish: p50 {number('latency p50 (s)') * 1000:.0f} ms, "
          f"p99 {number('latency p99 (s)') * 1000:.0f} ms")
    for k in dropped_keys():
        if number(k) > 0:
            print(f"{k}: {int(number(k))}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
