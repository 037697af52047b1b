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
rm -f "$log"
if [ -z "$summary" ]; then
  echo "ctest produced no summary"
  echo "0 passed, 1 failed"
  exit 1
fi
failed="$(sed -E 's/.* ([0-9]+) tests? failed out of ([0-9]+).*/\1/' <<<"$summary")"
total="$(sed -E 's/.* ([0-9]+) tests? failed out of ([0-9]+).*/\2/' <<<"$summary")"
echo "$((total - failed)) passed, ${failed} failed"
if [ "$status" -ne 0 ] || [ "$failed" -ne 0 ] || [ "$total" -eq 0 ]; then exit 1; fi
