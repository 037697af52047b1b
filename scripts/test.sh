#!/usr/bin/env bash
# Installs what is missing, builds, runs every unit test and ROS test, and ends with the line
# "N passed, N failed". Exits non-zero on any failure.
#   scripts/test.sh [ctest arguments, e.g. -R Octree]
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/.build}"

if ! "$ROOT/scripts/setup.sh"; then
  echo "setup or build failed"
  echo "0 passed, 1 failed"
  exit 1
fi

export PYENV_VERSION=system ROS_HOSTNAME=localhost
log="$(mktemp)"
(cd "$BUILD_DIR" && ctest --output-on-failure -j"$(nproc)" "$@") 2>&1 | tee "$log"
status=${PIPESTATUS[0]}

summary="$(grep -E '[0-9]+% tests passed, [0-9]+ tests? failed out of [0-9]+' "$log" | tail -n 1)"
if [ -z "$summary" ]; then
  rm -f "$log"
  echo "ctest produced no summary"
  echo "0 passed, 1 failed"
  exit 1
fi
failed="$(sed -E 's/.* ([0-9]+) tests? failed out of ([0-9]+).*/\1/' <<<"$summary")"
total="$(sed -E 's/.* ([0-9]+) tests? failed out of ([0-9]+).*/\2/' <<<"$summary")"
skipped="$(grep -c '(Skipped)' "$log" || true)"
# Why: a test that skips itself prints "SKIP: <reason>" (test/ros/two_hosts.sh without the rights
# for network namespaces); ctest keeps every test's output in LastTest.log.
while read -r name; do
  reason="$(awk -v t="$name" '/^[0-9]+\/[0-9]+ Test: / { cur = substr($0, index($0, "Test: ") + 6) }
    cur == t && /^SKIP: / { print substr($0, 7); exit }' "$BUILD_DIR/Testing/Temporary/LastTest.log" 2>/dev/null)"
  echo "[test] skipped: $name${reason:+ ($reason)}"
done < <(sed -nE 's/^[[:space:]]*[0-9]+ - (.*) \(Skipped\)$/\1/p' "$log")
rm -f "$log"
# A whole suite must run: a test binary that stopped being built, or a glob that lost its
# files, would otherwise pass by running less. Skipped tests (e.g. AVX2 paths on a CPU without
# it) are named by ctest above and counted here.
minimum="$(cat "$ROOT/test/minimum_test_count")"
short=0
if [ $# -eq 0 ] && [ "$total" -lt "$minimum" ]; then
  echo "only $total tests ran, at least $minimum expected (test/minimum_test_count)"
  short=1
fi
echo "[test] $skipped skipped"
echo "$((total - failed - skipped)) passed, ${failed} failed"
if [ "$status" -ne 0 ] || [ "$failed" -ne 0 ] || [ "$total" -eq 0 ] || [ "$short" -ne 0 ]; then exit 1; fi
