#!/usr/bin/env bash
# Builds and runs tools/bench/store_compare.cpp: LMDB vs RocksDB vs SQLite for paging map blocks.
#
#   tools/bench/store_compare.sh [DIR]        # DIR: where the stores are written (default: a
#                                             # mktemp dir under /tmp, removed afterwards)
#
# Environment: BLOCKS (default 200000), CRASH_RUNS (default 20), BUILD_DIR (default a mktemp dir,
# removed afterwards),
# TMPFS_RUN=0 to skip the second, shorter run on /dev/shm (zstd 1 only, no crash test),
# CONFIGS / CRASH_CONFIGS to pass --configs / --crash-configs through.
# Installs liblmdb-dev, librocksdb-dev, libsqlite3-dev, libzstd-dev and libcli11-dev (the command
# line) with apt-get when missing.
# Results: markdown tables on stdout (and results.txt in each run's folder while it runs).
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
blocks="${BLOCKS:-200000}"
crash_runs="${CRASH_RUNS:-20}"

missing=()
for p in liblmdb-dev librocksdb-dev libsqlite3-dev libzstd-dev libcli11-dev g++; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "installing ${missing[*]}" >&2
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${missing[@]}" >&2
fi

cleanup=()
trap 'for d in "${cleanup[@]}"; do rm -rf "$d"; done' EXIT
if [ -n "${BUILD_DIR:-}" ]; then
  build_dir="$BUILD_DIR"
  mkdir -p "$build_dir"
else
  build_dir="$(mktemp -d /tmp/store_compare_build.XXXXXX)"
  cleanup+=("$build_dir")
fi
g++ -std=c++17 -O2 -Wall -Wextra -I"$here/.." "$here/store_compare.cpp" -o "$build_dir/store_compare" \
  -llmdb -lrocksdb -lsqlite3 -lzstd

if [ $# -ge 1 ]; then
  dir="$1"
else
  dir="$(mktemp -d /tmp/store_compare.XXXXXX)"
  cleanup+=("$dir")
fi

extra=()
[ -n "${CONFIGS:-}" ] && extra+=(--configs "$CONFIGS")
[ -n "${CRASH_CONFIGS:-}" ] && extra+=(--crash-configs "$CRASH_CONFIGS")

echo "## $(date -u +%FT%TZ) $(uname -r), $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
echo "## disk: $dir ($(df -T "$dir" | awk 'NR==2 {print $2}')), $blocks blocks"
"$build_dir/store_compare" --blocks "$blocks" --crash-runs "$crash_runs" "${extra[@]}" "$dir"

if [ "${TMPFS_RUN:-1}" != 0 ] && [ -d /dev/shm ] && [ -w /dev/shm ]; then
  shm="$(mktemp -d /dev/shm/store_compare.XXXXXX)"
  cleanup+=("$shm")
  echo
  echo "## tmpfs: $shm, $blocks blocks, zstd 1 only, no crash test"
  "$build_dir/store_compare" --blocks "$blocks" --no-crash \
    --configs sqlite-normal:1,sqlite-full:1,lmdb:1,lmdb-madv:1,rocksdb:1,rocksdb-small:1 "$shm"
fi
