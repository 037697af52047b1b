#!/usr/bin/python3
"""Samples one process's memory until it exits, for tools/bench/building_bench.sh.

  rss_sample.py --pid PID --csv OUT.csv [--events OUT_events.csv] [--interval 0.5]
                [--frames-dir SEQ/disparity] [--out-dir DIR] [--store-dir DIR]

Every --interval seconds one CSV row: seconds since the process started (from /proc/PID/stat,
so the first rows are not lost to the sampler's own start), VmRSS, VmHWM, RssAnon, RssFile (MB =
2^20 bytes), the thread count, the last frame the process opened (inotify IN_OPEN on
--frames-dir: the fuser reads frame i's disparity NNNNNN.png when it fuses it; -1 before the
first), the bytes under --out-dir and under --store-dir (the page store's SQLite file and its
write-ahead log). --events gets a row per file created or renamed into --out-dir or
--store-dir and per 10th frame opened, with the same clock, to tell the phases of the run
apart (fusing, the map file, mesh.ply, the planning outputs). Python's standard library only
(inotify through ctypes).
"""
import argparse
import ctypes
import ctypes.util
import os
import struct
import sys
import time

IN_OPEN = 0x00000020
IN_CREATE = 0x00000100
IN_MOVED_TO = 0x00000080
IN_NONBLOCK = 0o4000


class Inotify:
    def __init__(self):
        self.libc = ctypes.CDLL(ctypes.util.find_library("c"), use_errno=True)
        self.fd = self.libc.inotify_init1(IN_NONBLOCK)
        if self.fd < 0:
            raise OSError(ctypes.get_errno(), "inotify_init1")
        self.watches = {}

    def watch(self, path, mask, kind):
        wd = self.libc.inotify_add_watch(self.fd, os.fsencode(path), mask)
        if wd < 0:
            raise OSError(ctypes.get_errno(), "inotify_add_watch " + path)
        self.watches[wd] = kind

    def read(self):
        """(kind, mask, name) of every event queued."""
        events = []
        while True:
            try:
                data = os.read(self.fd, 65536)
            except BlockingIOError:
                return events
            i = 0
            while i + 16 <= len(data):
                wd, mask, _cookie, length = struct.unpack_from("iIII", data, i)
                name = data[i + 16:i + 16 + length].rstrip(b"\0").decode(errors="replace")
                events.append((self.watches.get(wd, "?"), mask, name))
                i += 16 + length


def status_mb(pid):
    fields = {}
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            key, _, value = line.partition(":")
            if key in ("VmRSS", "VmHWM", "RssAnon", "RssFile", "Threads"):
                parts = value.split()
                fields[key] = int(parts[0]) / 1024.0 if key != "Threads" else int(parts[0])
    return fields


def start_seconds(pid):
    """The process's start on CLOCK_BOOTTIME, in seconds."""
    with open(f"/proc/{pid}/stat") as f:
        stat = f.read()
    after_comm = stat[stat.rindex(")") + 2:].split()
    return int(after_comm[19]) / os.sysconf("SC_CLK_TCK")  # field 22: starttime


def tree_bytes(path):
    total = 0
    if not path or not os.path.isdir(path):
        return 0
    for root, _dirs, files in os.walk(path):
        for name in files:
            try:
                total += os.stat(os.path.join(root, name)).st_size
            except OSError:
                pass  # removed meanwhile (a map file's temporary, a store at the end)
    return total


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--pid", type=int, required=True)
    ap.add_argument("--csv", required=True)
    ap.add_argument("--events")
    ap.add_argument("--interval", type=float, default=0.5)
    ap.add_argument("--frames-dir")
    ap.add_argument("--out-dir")
    ap.add_argument("--store-dir")
    args = ap.parse_args()

    notify = Inotify()
    if args.frames_dir:
        notify.watch(args.frames_dir, IN_OPEN, "frame")
    for kind, path in (("out", args.out_dir), ("store", args.store_dir)):
        if path:
            os.makedirs(path, exist_ok=True)
            notify.watch(path, IN_CREATE | IN_MOVED_TO, kind)
    try:
        t0 = start_seconds(args.pid)
    except OSError:
        sys.exit(f"rss_sample: no process {args.pid}")

    frame = -1
    events = open(args.events, "w") if args.events else None
    if events:
        events.write("t_s,kind,what\n")
    with open(args.csv, "w") as out:
        out.write("t_s,rss_mb,hwm_mb,anon_mb,file_mb,threads,frame,out_mb,store_mb\n")
        while True:
            now = time.clock_gettime(time.CLOCK_BOOTTIME) - t0
            try:
                s = status_mb(args.pid)
            except (OSError, ValueError):
                break  # the process ended
            if "VmRSS" not in s:
                break  # a zombie: its memory is gone
            for kind, mask, name in notify.read():
                if kind == "frame" and mask & IN_OPEN:
                    stem = name.split(".")[0]
                    if stem.isdigit():
                        frame = max(frame, int(stem))
                        if events and int(stem) % 10 == 0:
                            events.write(f"{now:.2f},frame,{int(stem)}\n")
                elif events and kind in ("out", "store"):
                    events.write(f"{now:.2f},{kind},{name}\n")
            out.write(
                f"{now:.2f},{s['VmRSS']:.1f},{s['VmHWM']:.1f},{s.get('RssAnon', 0):.1f},"
                f"{s.get('RssFile', 0):.1f},{s.get('Threads', 0)},{frame},"
                f"{tree_bytes(args.out_dir) / 1048576.0:.1f},"
                f"{tree_bytes(args.store_dir) / 1048576.0:.1f}\n")
            out.flush()
            if events:
                events.flush()
            time.sleep(args.interval)
    if events:
        # What happened after the last sample (the last outputs), at the time the end was seen.
        now = time.clock_gettime(time.CLOCK_BOOTTIME) - t0
        for kind, mask, name in notify.read():
            if kind in ("out", "store"):
                events.write(f"{now:.2f},{kind},{name}\n")
        events.close()


if __name__ == "__main__":
    main()
