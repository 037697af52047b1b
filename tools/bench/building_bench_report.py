#!/usr/bin/python3
"""The figures and the plot of tools/bench/building_bench.sh's two runs.

  building_bench_report.py <work-dir> <results-dir> <cap-mb>

Reads <work-dir>/{uncapped,capped}/stats.json, *_rss.csv, *_events.csv, *.wall and cmp.csv;
writes <results-dir>/figures.md (the tables) and <results-dir>/rss.png (RSS over time of both
runs, the cap + baseline + 64 MB line, where each run's fusing ends and its outputs begin).
Baseline: the resident set before the first frame (stats.json memory.start_rss_megabytes, read
by the fuser itself once the input is open); the RSS after the first frames is given beside it.
"""
import csv
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

work, results, cap_mb = sys.argv[1], sys.argv[2], float(sys.argv[3])
RUNS = ("uncapped", "capped")


def load_csv(path):
    with open(path) as f:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]


def load_events(path):
    with open(path) as f:
        return [(float(r["t_s"]), r["kind"], r["what"]) for r in csv.DictReader(f)]


def first_event(events, kind, predicate):
    for t, k, what in events:
        if k == kind and predicate(what):
            return t
    return None


data = {}
for run in RUNS:
    stats = json.load(open(os.path.join(work, run, "stats.json")))
    rows = load_csv(os.path.join(work, f"{run}_rss.csv"))
    events = load_events(os.path.join(work, f"{run}_events.csv"))
    start, end, status = open(os.path.join(work, f"{run}.wall")).read().split()
    last_frame = max(r["frame"] for r in rows)
    # Fusing ends when the last frame has been opened and fused: the first output file appears
    # (the map file's temporary, mesh.ply otherwise).
    t_outputs = first_event(events, "out", lambda w: True)
    t_last_frame = next(r["t_s"] for r in rows if r["frame"] == last_frame)
    data[run] = dict(stats=stats, rows=rows, events=events, wall=float(end) - float(start),
                     status=int(status), last_frame=last_frame, t_outputs=t_outputs,
                     t_last_frame=t_last_frame)

base = data["capped"]["stats"]["memory"]["start_rss_megabytes"]
threshold = cap_mb + base + 64.0


def rss_after_frames(rows, n):
    for r in rows:
        if r["frame"] >= n:
            return r["rss_mb"]
    return float("nan")


def phase_peak(rows, lo, hi):
    v = [r["rss_mb"] for r in rows if lo <= r["t_s"] < hi]
    return max(v) if v else float("nan")


def above(rows, limit, lo=0.0, hi=float("inf")):
    """Seconds sampled above `limit` between lo and hi (0.5 s per sample), and the first time."""
    ts = [r["t_s"] for r in rows if r["rss_mb"] > limit and lo <= r["t_s"] < hi]
    dt = rows[1]["t_s"] - rows[0]["t_s"] if len(rows) > 1 else 0.5
    return len(ts) * dt, (ts[0] if ts else None)


lines = []
w = lines.append
w(f"Cap {cap_mb:g} MB; baseline (capped run's RSS before the first frame, stats.json "
  f"`memory.start_rss_megabytes`) {base:.1f} MB; cap + baseline + 64 MB = {threshold:.1f} MB.\n")
w("| figure | uncapped | capped |")
w("|---|---|---|")


def row(name, f):
    w(f"| {name} | " + " | ".join(f(data[r]) for r in RUNS) + " |")


row("exit status", lambda d: str(d["status"]))
row("frames fused", lambda d: str(d["stats"]["frames"]["used"]))
row("wall time of the process (s)", lambda d: f"{d['wall']:.1f}")
row("stats.json wall_time_s (frames only, no outputs)", lambda d: f"{d['stats']['wall_time_s']:.1f}")
row("process wall - wall_time_s: start-up and the outputs (s)",
    lambda d: f"{d['wall'] - d['stats']['wall_time_s']:.1f}")
row("peak RSS, VmHWM last sampled (MB)", lambda d: f"{max(r['hwm_mb'] for r in d['rows']):.1f}")
row("peak RSS, stats.json peak_rss_megabytes (MB)",
    lambda d: f"{d['stats']['memory']['peak_rss_megabytes']:.1f}")
row("RSS before the first frame, start_rss_megabytes (MB)",
    lambda d: f"{d['stats']['memory']['start_rss_megabytes']:.1f}")
row("RSS once frame 1 is opened (MB)", lambda d: f"{rss_after_frames(d['rows'], 1):.1f}")
row("RSS once frame 10 is opened (MB)", lambda d: f"{rss_after_frames(d['rows'], 10):.1f}")
row("peak RSS while fusing, until the last frame is opened (MB)",
    lambda d: f"{phase_peak(d['rows'], 0, d['t_last_frame']):.1f}")
row("peak RSS after: last frame, final mesh and planning pass, outputs (MB)",
    lambda d: f"{phase_peak(d['rows'], d['t_last_frame'], 1e9):.1f}")
row("RSS when the last frame is opened (MB)",
    lambda d: f"{next(r['rss_mb'] for r in d['rows'] if r['t_s'] >= d['t_last_frame']):.1f}")
row("last frame opened at (s since start)", lambda d: f"{d['t_last_frame']:.1f}")
row(f"time above {threshold:.0f} MB while fusing (s)",
    lambda d: f"{above(d['rows'], threshold, 0, d['t_last_frame'])[0]:.1f}")
row(f"time above {threshold:.0f} MB after the last frame (s)",
    lambda d: f"{above(d['rows'], threshold, d['t_last_frame'])[0]:.1f}")
row(f"first time above {threshold:.0f} MB (s; frame then)",
    lambda d: (lambda t: "never" if t is None else
               f"{t:.1f} (frame {int(next(r['frame'] for r in d['rows'] if r['t_s'] >= t))})")(
        above(d["rows"], threshold)[1]))
row("map memory at the end, paging.map_memory_megabytes (MB)",
    lambda d: f"{d['stats']['paging']['map_memory_megabytes']:.1f}")
row("blocks in memory at the end / paged out", lambda d: "{} / {}".format(
    d["stats"]["blocks"]["total"], d["stats"]["paging"]["blocks_paged_out_now"]))
row("TSDF in memory at the end, memory.megabytes (MB)",
    lambda d: f"{d['stats']['memory']['megabytes']:.1f}")
row("submeshes in memory at the end, mesh_store_megabytes (MB)",
    lambda d: f"{d['stats']['memory']['mesh_store_megabytes']:.1f}")
row("welded mesh for mesh.ply, mesh_output_megabytes (MB)",
    lambda d: f"{d['stats']['memory']['mesh_output_megabytes']:.1f}")
row("file pages at the end, file_rss_megabytes (MB)",
    lambda d: f"{d['stats']['memory']['file_rss_megabytes']:.1f}")
for key in ("total", "lookup", "fusion", "meshing", "paging"):
    row(f"timings_ms.{key} p50 / p99 / mean (ms, per {data['capped']['stats']['timings_ms'][key]['per']})",
        lambda d, key=key: "{p50:.1f} / {p99:.1f} / {mean:.1f}".format(**d["stats"]["timings_ms"][key]))
row("timings_ms.page_in p50 / p99 / mean (ms, per frame that paged in)",
    lambda d: "{p50:.1f} / {p99:.1f} / {mean:.1f}".format(**d["stats"]["timings_ms"]["page_in"]))
row("paging p50 / total p50 (share of frame time)",
    lambda d: "{:.1%}".format(d["stats"]["timings_ms"]["paging"]["p50"] /
                              d["stats"]["timings_ms"]["total"]["p50"]))
row("paging mean / total mean",
    lambda d: "{:.1%}".format(d["stats"]["timings_ms"]["paging"]["mean"] /
                              d["stats"]["timings_ms"]["total"]["mean"]))
w("")
w("`paging` of the capped run's stats.json:\n")
w("```json")
w(json.dumps(data["capped"]["stats"]["paging"], indent=1))
w("```")
w("")
w("Output events of the capped run (seconds since the process started; sampled every 0.5 s):\n")
for t, kind, what in data["capped"]["events"]:
    if kind != "frame":
        w(f"- {t:.1f} s: {kind} `{what}`")
w("")
w("Output events of the uncapped run:\n")
for t, kind, what in data["uncapped"]["events"]:
    if kind != "frame":
        w(f"- {t:.1f} s: {kind} `{what}`")
w("")
with open(os.path.join(work, "cmp.csv")) as f:
    cmp_rows = list(csv.DictReader(f))
w("Byte comparison (`cmp`) of every output but stats.json, capped against uncapped:\n")
w("| file | bytes | result |")
w("|---|---|---|")
for r in cmp_rows:
    w(f"| {r['file']} | {r['bytes']} | {r['cmp']} |")
open(os.path.join(results, "figures.md"), "w").write("\n".join(lines) + "\n")
print("\n".join(lines))

fig, (ax, axc, axf) = plt.subplots(3, 1, figsize=(11, 11), sharex=True,
                                   gridspec_kw={"height_ratios": [3, 3, 1.2]})
colours = {"uncapped": "tab:blue", "capped": "tab:red"}
for run in RUNS:
    d = data[run]
    t = [r["t_s"] for r in d["rows"]]
    label = (f"{run}: peak {d['stats']['memory']['peak_rss_megabytes']:.0f} MB, "
             f"{d['wall']:.0f} s")
    ax.plot(t, [r["rss_mb"] for r in d["rows"]], color=colours[run], label=label, lw=1.2)
    axf.plot(t, [r["frame"] for r in d["rows"]], color=colours[run], lw=1.2)
    for a in (ax, axc, axf):
        a.axvline(d["t_last_frame"], color=colours[run], ls=":", lw=1,
                  label=f"{run}: last frame opened; then final passes, map file, mesh.ply"
                  if a is ax else None)
for a in (ax, axc):
    a.axhline(threshold, color="black", ls="--", lw=1,
              label=f"cap {cap_mb:g} + baseline {base:.0f} + 64 = {threshold:.0f} MB")
    a.axhline(base, color="grey", ls=":", lw=1,
              label=f"baseline (RSS before frame 0) {base:.0f} MB")
ax.set_ylabel("resident set (MB)")
ax.set_ylim(bottom=0)
ax.legend(loc="upper left", fontsize=8)
ax.grid(True, alpha=0.3)
ax.set_title(f"stereo_fusion_fuse on {os.path.basename(os.path.normpath(work))}: "
             f"RSS every 0.5 s, uncapped and capped at {cap_mb:g} MB")
capped_rows = data["capped"]["rows"]
tc = [r["t_s"] for r in capped_rows]
axc.plot(tc, [r["rss_mb"] for r in capped_rows], color="tab:red", lw=1.2, label="capped: RSS")
axc.plot(tc, [r["anon_mb"] for r in capped_rows], color="tab:purple", lw=1,
         label="capped: anonymous (heap) part of RSS")
axc.plot(tc, [r["file_mb"] for r in capped_rows], color="tab:green", lw=1,
         label="capped: file-backed part of RSS")
axc.set_ylim(0, max(max(r["rss_mb"] for r in capped_rows), threshold) * 1.1)
axc.set_ylabel("capped run (MB)")
axs = axc.twinx()
axs.plot(tc, [r["store_mb"] for r in capped_rows], color="tab:orange", lw=1, ls="--",
         label="page store on disk (right axis)")
axs.set_ylabel("page store on disk (MB)", color="tab:orange")
h1, l1 = axc.get_legend_handles_labels()
h2, l2 = axs.get_legend_handles_labels()
axc.legend(h1 + h2, l1 + l2, loc="upper left", fontsize=8)
axc.grid(True, alpha=0.3)
axf.set_ylabel("frame fused")
axf.set_xlabel("seconds since the process started")
axf.grid(True, alpha=0.3)
fig.tight_layout()
fig.savefig(os.path.join(results, "rss.png"), dpi=110)

# The same RSS against the frame being fused: the two runs side by side at each frame.
fig, ax = plt.subplots(figsize=(11, 5))
for run in RUNS:
    rows = [r for r in data[run]["rows"] if r["frame"] >= 0 and r["t_s"] <= data[run]["t_last_frame"]]
    ax.plot([r["frame"] for r in rows], [r["rss_mb"] for r in rows], color=colours[run],
            lw=1.2, label=f"{run}: RSS while fusing (before the outputs)")
capped_rows = [r for r in data["capped"]["rows"]
               if r["frame"] >= 0 and r["t_s"] <= data["capped"]["t_last_frame"]]
ax.plot([r["frame"] for r in capped_rows], [r["anon_mb"] for r in capped_rows],
        color="tab:purple", lw=1, label="capped: anonymous part")
ax.axhline(threshold, color="black", ls="--", lw=1,
           label=f"cap {cap_mb:g} + baseline {base:.0f} + 64 = {threshold:.0f} MB")
ax.set_xlabel("frame (last one opened)")
ax.set_ylabel("resident set (MB)")
ax.set_ylim(bottom=0)
ax.grid(True, alpha=0.3)
ax.legend(loc="upper left", fontsize=8)
ax.set_title("RSS against the frame being fused")
fig.tight_layout()
fig.savefig(os.path.join(results, "rss_by_frame.png"), dpi=110)
