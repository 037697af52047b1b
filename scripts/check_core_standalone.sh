#!/usr/bin/env bash
# Builds the core alone, as the plain CMake project cmake/core/ (stereo_fusion_core and its unit
# tests, without catkin or any ROS package), in a temporary folder outside the repository, and
# runs its tests. Fails when the core or its unit tests come to need catkin, ROS, rosbag or a tool:
#   - the configure finds only Eigen, OpenCV, yaml-cpp, zlib, Threads and GTest; a catkin or ROS
#     package in its cache is an error;
#   - the link has no ROS library to resolve a ROS symbol;
#   - Debian installs ROS headers in /usr/include, where an #include of one would compile, so the
#     compiler's dependency files are checked too: no object may be compiled from a header of a
#     ROS package (Debian's ROS packages have their homepage on ros.org).
# Ends with "core standalone: N tests passed" or a reason.
#   scripts/check_core_standalone.sh [ctest arguments, e.g. -R MapFile]
# Environment: CORE_BUILD_DIR (kept when given, e.g. .build-core: inside the repository only a dot
#   folder, see ros-on-debian pitfall 3; default a new folder in $TMPDIR, removed at the end),
#   CHECK_JOBS (default 2) compile jobs and parallel tests, BUILD_TYPE (default Release),
#   CORE_SANITIZE (e.g. address,undefined: the core and its tests built with those sanitizers at
#   -O1 -g1, as scripts/check.sh's ASan step does, so one build proves both).
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
JOBS="${CHECK_JOBS:-2}"

# The Debian packages (the same list as the full build; only missing ones are installed).
"$ROOT/scripts/setup.sh" --no-build || { echo "core standalone: setup failed"; exit 1; }

if [ -n "${CORE_BUILD_DIR:-}" ]; then
  BUILD_DIR="$CORE_BUILD_DIR"
  mkdir -p "$BUILD_DIR"
else
  BUILD_DIR="$(mktemp -d "${TMPDIR:-/tmp}/stereo_fusion_core.XXXXXX")"
  trap 'rm -rf "$BUILD_DIR"' EXIT
fi
fail() { echo "core standalone: $*"; exit 1; }

LAUNCHER=()
if command -v ccache >/dev/null 2>&1; then LAUNCHER=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
BUILD_FLAGS=(-DCMAKE_BUILD_TYPE="${BUILD_TYPE:-Release}")
if [ -n "${CORE_SANITIZE:-}" ]; then
  # -O1 -g1 and assertions on: the sanitizer builds' flags (scripts/check.sh says why).
  BUILD_FLAGS=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1"
               -DSTEREO_FUSION_SANITIZE="$CORE_SANITIZE")
fi
echo "[core] configuring cmake/core/ in $BUILD_DIR (${BUILD_FLAGS[*]})"
cmake -S "$ROOT/cmake/core" -B "$BUILD_DIR" "${BUILD_FLAGS[@]}" "${LAUNCHER[@]}" \
  >"$BUILD_DIR/configure.log" 2>&1 || { cat "$BUILD_DIR/configure.log"; fail "configure failed"; }
ros_in_cache="$(grep -E '^(catkin|roscpp|rosbag|rostest|cpp_common|rosconsole|roslib)[A-Za-z_]*_DIR:' \
  "$BUILD_DIR/CMakeCache.txt" || true)"
[ -z "$ros_in_cache" ] || fail "the configure found catkin / ROS packages: $ros_in_cache"

# The stamp tells scripts/check.sh that this run's core was built (its objects are linked by the
# catkin ASan build); a failed build leaves none, so older objects are never taken for it.
rm -f "$BUILD_DIR/core_built.stamp"
cmake --build "$BUILD_DIR" -j"$JOBS" || fail "build failed"
touch "$BUILD_DIR/core_built.stamp"

# Headers every object was compiled from (Makefile generator: <object>.o.d next to each object).
mapfile -t headers < <(find "$BUILD_DIR" -name '*.o.d' -exec cat {} + | tr ' \\' '\n\n' |
  grep -E '^/.*\.(h|hh|hpp|hxx|inl)$' | xargs -r realpath -s -m | grep -v "^$ROOT/" | sort -u)
[ "${#headers[@]}" -gt 0 ] || fail "no dependency files found in $BUILD_DIR"
if command -v dpkg-query >/dev/null 2>&1; then
  mapfile -t packages < <(dpkg-query -S "${headers[@]}" 2>/dev/null | sed -E 's/: .*//; s/, /\n/g' |
    sed -E 's/:.*//' | sort -u)
  ros_packages=()
  for package in "${packages[@]}"; do
    homepage="$(dpkg-query -W -f='${Homepage}' "$package" 2>/dev/null || true)"
    if [[ "$homepage" =~ ros\.org|github\.com/ros ]]; then ros_packages+=("$package"); fi
  done
  if [ "${#ros_packages[@]}" -gt 0 ]; then
    for package in "${ros_packages[@]}"; do
      echo "  headers of $package:"
      dpkg-query -L "$package" | grep -Fx -f <(printf '%s\n' "${headers[@]}") | sed 's/^/    /' | head -n 5
    done
    fail "the core or its tests include headers of ROS packages: ${ros_packages[*]}"
  fi
  echo "[core] ${#headers[@]} system headers used, from ${#packages[@]} Debian packages, none of ROS"
else
  echo "[core] dpkg-query not found: ROS header check skipped"
fi

echo "[core] running the core's unit tests"
log="$BUILD_DIR/ctest.log"
(cd "$BUILD_DIR" && ctest --output-on-failure -j"$JOBS" "$@") 2>&1 | tee "$log"
status=${PIPESTATUS[0]}
summary="$(grep -E '[0-9]+% tests passed, [0-9]+ tests? failed out of [0-9]+' "$log" | tail -n 1)"
[ -n "$summary" ] || fail "ctest produced no summary"
total="$(sed -E 's/.* failed out of ([0-9]+).*/\1/' <<<"$summary")"
if [ "$status" -ne 0 ] || [ "$total" -eq 0 ]; then fail "$summary"; fi
echo "core standalone: $total tests passed"
