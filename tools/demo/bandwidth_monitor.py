#!/usr/bin/python3
"""Counts the serialized bytes of topics while a bag plays through stereo_fusion, until every
expected frame is accounted for in /diagnostics (fused + dropped) and the last update was sent.
Prints one line per topic: messages, bytes, and bytes/s over the recording's duration (the rate a
link to a base station must carry when the robot runs live). Used by scripts/bandwidth.sh."""
import argparse
import json
import threading
import time

import rospy
from diagnostic_msgs.msg import DiagnosticArray

lock = threading.Lock()
counts = {}
values = {}


def on_message(msg, topic):
    with lock:
        n, b = counts.get(topic, (0, 0))
        counts[topic] = (n + 1, b + len(msg._buff))  # AnyMsg keeps the serialized bytes


def on_diagnostics(msg):
    for status in msg.status:
        if "fusion" in status.name:
            values.update({kv.key: kv.value for kv in status.values})


def number(key):
    try:
        return float(values.get(key, 0))
    except ValueError:
        return 0.0


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--frames", type=int, required=True, help="frames the bag holds")
    parser.add_argument("--duration-s", type=float, required=True, help="the bag's duration (sim time)")
    parser.add_argument("--label", default="")
    parser.add_argument("--json", help="append the result as one JSON line to this file")
    parser.add_argument("topics", nargs="+")
    args = parser.parse_args(rospy.myargv()[1:])
    rospy.init_node("stereo_fusion_bandwidth", anonymous=True, disable_signals=True)
    for topic in args.topics:
        rospy.Subscriber(topic, rospy.AnyMsg, on_message, callback_args=topic, queue_size=1000)
    rospy.Subscriber("/diagnostics", DiagnosticArray, on_diagnostics)
    deadline = time.time() + 600
    while time.time() < deadline:
        time.sleep(1.0)
        # Every "dropped: …" counter (one per reason of the node's table) accounts for a frame.
        drops = [k for k in list(values) if k.startswith("dropped: ")]
        if number("frames fused") + sum(number(k) for k in drops) >= args.frames:
            break
    time.sleep(3.0)  # the last rate-limited update is flushed within 1 / mesh_publish_rate_hz
    result = {"label": args.label, "frames_fused": int(number("frames fused")), "duration_s": args.duration_s,
              "topics": {}}
    with lock:
        for topic in args.topics:
            n, b = counts.get(topic, (0, 0))
            result["topics"][topic] = {"messages": n, "bytes": b, "bytes_per_s": b / args.duration_s}
            print(f"[bandwidth] {args.label:<8} {topic:<32} {n:5d} msgs {b:12d} B {b / args.duration_s:12.0f} B/s",
                  flush=True)
    if args.json:
        with open(args.json, "a") as f:
            f.write(json.dumps(result) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
