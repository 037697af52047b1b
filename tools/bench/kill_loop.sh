#!/usr/bin/env bash
# The map store under SIGKILL: fuses <sequence> with checkpoints every <period> seconds, kills
# the fuser at a random instant, resumes the store to the end, and checks that every store
# reopens, what each kill lost (frames fused after the last committed checkpoint, and how long
# before the kill that checkpoint's last frame was fused), and that every resumed run's outputs
# are byte-identical to an uninterrupted run's.
#
#   tools/bench/kill_loop.sh <sequence> <work-dir> [kills=50] [period_s=1] [fuse args ...]
#
# e.g. tools/bench/kill_loop.sh /work/data/room /tmp/kills 50 1 --set voxel_size_m=0.02
# Prints one line per kill and a summary; <work-dir>/kills.csv holds the figures.
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/../.." && pwd)"
SEQ="$1"
WORK="$2"
KILLS="${3:-50}"
PERIOD="${4:-1}"
shift $(($# < 4 ? $# : 4))
EXTRA=("$@")
FUSE="${BUILD_DIR:-$ROOT/.build}/devel/lib/stereo_fusion/stereo_fusion_fuse"
OUTPUTS=(mesh.ply esdf.ply occupancy.pgm octomap.bt)

rm -rf "$WORK"
mkdir -p "$WORK"
now() { date +%s.%N; }

echo "uninterrupted reference run ..."
start=$(now)
"$FUSE" "$SEQ" "$WORK/reference" --quiet "${EXTRA[@]}" > /dev/null 2>&1
end=$(now)
duration=$(/usr/bin/python3 -c "print(round($end - $start, 3))")
echo "reference: ${duration} s"

echo "kill,kill_after_s,frames_fused_before_kill,checkpointed_next_frame,lost_frames,lost_span_s,reopened,identical" \
  > "$WORK/kills.csv"
for ((k = 1; k <= KILLS; ++k)); do
  store="$WORK/store"
  log="$WORK/frames.log"
  rm -rf "$store" "$log" "$WORK/killed" "$WORK/resumed"
  # A random instant in (0.2 s, 95 % of the run): before the first checkpoint, during one, between.
  delay=$(/usr/bin/python3 -c "import random; print(round(random.uniform(0.2, 0.95 * $duration), 3))")
  start=$(now)
  "$FUSE" "$SEQ" "$WORK/killed" --quiet --frame-log "$log" "${EXTRA[@]}" \
    --set checkpoint_period_s="$PERIOD" --set map_store_path="$store" > /dev/null 2>&1 &
  pid=$!
  sleep "$delay"
  kill_time=$(now)
  kill -9 "$pid" 2> /dev/null || true
  wait "$pid" 2> /dev/null || true
  reopened=1
  if ! "$FUSE" "$SEQ" "$WORK/resumed" --quiet "${EXTRA[@]}" --set resume=true \
    --set map_store_path="$store" > "$WORK/resume.log" 2>&1; then
    reopened=0
  fi
  identical=1
  for f in "${OUTPUTS[@]}"; do
    cmp -s "$WORK/reference/$f" "$WORK/resumed/$f" || identical=0
  done
  /usr/bin/python3 - "$log" "$WORK/resumed/stats.json" "$kill_time" "$start" "$k" "$reopened" \
    "$identical" >> "$WORK/kills.csv" << 'EOF'
import json, os, sys
log, stats, kill_time, start, k, reopened, identical = sys.argv[1:]
fused = []
if os.path.exists(log):
    for line in open(log):
        i, t = line.split()
        fused.append((int(i), float(t)))
next_frame = 0
if os.path.exists(stats):
    next_frame = json.load(open(stats))["map_store"]["resumed_from_frame"]
lost = [f for f in fused if f[0] >= next_frame]
kept = [f for f in fused if f[0] < next_frame]
# How long before the kill the last checkpointed frame was fused (0 frames kept: since start).
since = float(kill_time) - (kept[-1][1] if kept else float(start))
print(f"{k},{float(kill_time) - float(start):.3f},{len(fused)},{next_frame},{len(lost)},"
      f"{since:.3f},{reopened},{identical}")
EOF
  tail -n 1 "$WORK/kills.csv"
done

/usr/bin/python3 - "$WORK/kills.csv" "$PERIOD" << 'EOF'
import csv, statistics, sys
rows = list(csv.DictReader(open(sys.argv[1])))
period = float(sys.argv[2])
lost = [int(r["lost_frames"]) for r in rows]
span = [float(r["lost_span_s"]) for r in rows]
print(f"kills: {len(rows)}; stores reopened: {sum(int(r['reopened']) for r in rows)}; "
      f"resumed runs byte-identical to the uninterrupted one: {sum(int(r['identical']) for r in rows)}")
print(f"frames lost per kill: median {statistics.median(lost)}, max {max(lost)}")
print(f"age of the last checkpointed frame at the kill (s): median {statistics.median(span):.2f}, "
      f"max {max(span):.2f} (checkpoint_period_s {period})")
EOF
