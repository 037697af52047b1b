#!/usr/bin/env bash
# Builds one libFuzzer target (clang, ASan + UBSan) in .build-fuzz/ and runs it.
#   scripts/fuzz.sh <target> [seconds, default 600] [more libFuzzer options...]
#   scripts/fuzz.sh --list
# <target> is a test/fuzz/fuzz_<name>.cpp, given as fuzz_<name> or <name>. The run starts from
# the checked-in seeds (test/fuzz/corpus/<target>/) and keeps what it finds in .fuzz/<target>/:
# corpus/ (new inputs) and crash-*, leak-*, timeout-*, oom-* (findings). It ends with a summary
# line and exits non-zero when there is a finding. Turn a finding into a regression test by
# copying it to test/fuzz/regressions/<target>/ (ctest replays it in the normal build).
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${FUZZ_BUILD_DIR:-$ROOT/.build-fuzz}"

if [ "${1:-}" = "--list" ] || [ $# -lt 1 ]; then
  echo "usage: scripts/fuzz.sh <target> [seconds] [libFuzzer options]; targets:"
  for f in "$ROOT"/test/fuzz/fuzz_*.cpp; do
    [ "$(basename "$f")" = fuzz_replay_main.cpp ] || echo "  $(basename "$f" .cpp)"
  done
  [ $# -ge 1 ]; exit $?
fi
target="$1"
[[ "$target" == fuzz_* ]] || target="fuzz_$target"
seconds="${2:-600}"
shift $(($# >= 2 ? 2 : 1))
if [ ! -f "$ROOT/test/fuzz/$target.cpp" ] || [ "$target" = fuzz_replay_main ]; then
  echo "no fuzz target test/fuzz/$target.cpp (scripts/fuzz.sh --list)" >&2
  exit 2
fi

"$ROOT/scripts/setup.sh" --no-build --with fuzz || exit 1
export PYENV_VERSION=system
LAUNCHER=()
if command -v ccache >/dev/null 2>&1; then LAUNCHER=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
# -O2 -g: libFuzzer's speed with readable stacks; no NDEBUG, so our assertions are checked too,
# but not Eigen's per-coefficient ones (they made fusion 10x slower; ASan checks the bounds).
# Tests are off: the fuzz build needs only the core and the targets.
cmake -S "$ROOT" -B "$BUILD_DIR" -DCMAKE_C_COMPILER=clang-14 -DCMAKE_CXX_COMPILER=clang++-14 \
  "${LAUNCHER[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g -DEIGEN_NO_DEBUG" \
  -DSTEREO_FUSION_FUZZ=ON -DCATKIN_ENABLE_TESTING=OFF \
  -DPYTHON_EXECUTABLE=/usr/bin/python3 -DPython3_EXECUTABLE=/usr/bin/python3 \
  >"$BUILD_DIR.configure.log" 2>&1 || { cat "$BUILD_DIR.configure.log"; exit 1; }
cmake --build "$BUILD_DIR" -j2 --target "$target" || exit 1
binary="$(find "$BUILD_DIR" -type f -name "$target" -perm -u+x | head -n 1)"

work="$ROOT/.fuzz/$target"
mkdir -p "$work/corpus"
seeds="$ROOT/test/fuzz/corpus/$target"
log="$work/run-$(date +%Y%m%d-%H%M%S).log"
echo "[fuzz] $target for ${seconds}s; corpus $work/corpus + $seeds; log $log"
# Scratch files of the file-reading targets go to memory when it can, in a folder of this run:
# libFuzzer ends with _Exit(), so the targets cannot remove their own.
scratch_base=/tmp
if [ -d /dev/shm ] && [ -w /dev/shm ]; then scratch_base=/dev/shm; fi
TMPDIR="$(mktemp -d "$scratch_base/stereo_fusion_fuzz_run.XXXXXX")"
export TMPDIR
trap 'rm -rf "$TMPDIR"' EXIT
touch "$work/.started"
started=$SECONDS
# The first corpus folder receives new inputs; the seeds stay untouched.
"$binary" "$work/corpus" "$seeds" -max_total_time="$seconds" -timeout=30 -max_len=4096 \
  -artifact_prefix="$work/" -print_final_stats=1 "$@" >"$log" 2>&1
status=$?
elapsed=$((SECONDS - started))

done_line="$(grep -E '^#[0-9]+[[:space:]]+DONE' "$log" | tail -n 1)"
[ -n "$done_line" ] || done_line="$(grep -E '^#[0-9]+[[:space:]]' "$log" | tail -n 1)"
stat() { grep -E "^stat::$1:" "$log" | awk '{print $2}' | tail -n 1; }
findings=$(find "$work" -maxdepth 1 -type f \( -name 'crash-*' -o -name 'leak-*' -o -name 'timeout-*' \
  -o -name 'oom-*' -o -name 'slow-unit-*' \) -newer "$work/.started" 2>/dev/null | sort)
echo "[fuzz] last status line: $done_line"
echo "[fuzz] $target: $(stat number_of_executed_units) execs in ${elapsed}s, $(stat average_exec_per_sec) exec/s," \
     "$(stat new_units_added) new units, corpus $(find "$work/corpus" -type f | wc -l) files," \
     "peak rss $(stat peak_rss_mb) MB, exit $status"
if [ "$status" -ne 0 ] || [ -n "$findings" ]; then
  echo "$findings"
  grep -E 'ERROR: |SUMMARY: |Test unit written to' "$log" | head -n 5
  echo "[fuzz] FINDING: see $log"
  exit 1
fi
echo "[fuzz] no findings"
