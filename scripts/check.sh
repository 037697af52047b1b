#!/usr/bin/env bash
# Sanitizer checks: builds the unit tests with sanitizers in their own build folders and runs
# them; any sanitizer report or test failure makes it exit non-zero. Ends with a summary.
#   scripts/check.sh [--asan | --tsan | --all]      (default --all)
#   --asan  AddressSanitizer + UndefinedBehaviorSanitizer (g++): the core's unit tests in the
#           standalone core build (scripts/check_core_standalone.sh, in .build-core-asan/, which
#           also proves the core builds without ROS), and in .build-asan/, which links that
#           core's objects (cmake/core/prebuilt_core.cmake), the tools' unit tests and every fuzz
#           target's checked-in corpus and regressions (test/fuzz/)
#   --tsan  ThreadSanitizer (g++), in .build-tsan/: the tests that run code on several threads
#           (test/unit/thread_tests.cmake)
# --asan also runs the ROS code under ASan + UBSan (+ LeakSanitizer): the nodelet and the
# assembler built with them, loaded into the package's own nodelet manager (stereo_fusion_manager,
# also built with them) and driven by the rostests with a real master: fusion_nodelet.test (every
# message type, services, bad input), mesh_assembler.test (the base-station stream) and
# overload.test. A report in any of those processes fails the step (.check-logs/asan_ros.output.log).
# --tsan runs the same rostests under TSan. roscpp, nodelet and bondcpp are not instrumented, so
# TSan cannot order the boost::shared_ptr hand-overs between their threads and ours:
# test/tsan_suppressions.txt names the library-internal frames of those reports, each with why.
# Both run with STEREO_FUSION_TEST_QUICK=1: the three heaviest thread tests use smaller inputs
# (test/unit/QuickMode.h); under ASan the mapper's thread-count test alone took 150 s otherwise.
# Environment: CHECK_JOBS (default 2) parallel compile jobs and test shards.
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
JOBS="${CHECK_JOBS:-2}"
mode=--all
for arg in "$@"; do
  case "$arg" in
    --asan | --tsan | --all) mode="$arg" ;;
    *) echo "usage: scripts/check.sh [--asan | --tsan | --all]" >&2; exit 2 ;;
  esac
done

"$ROOT/scripts/setup.sh" --no-build --with sanitizers || { echo "check: setup failed"; exit 1; }
export PYENV_VERSION=system ROS_HOSTNAME=localhost
LAUNCHER=()
if command -v ccache >/dev/null 2>&1; then LAUNCHER=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi

results=()  # one summary line per step
failed=0
start=$SECONDS

# build <dir> <sanitizers> <targets...>: configure (catkin needs the whole project) and build
# only the given targets (the unit tests, and the ROS targets its rostest steps need). Extra
# configure arguments come in the array BUILD_ARGS.
BUILD_ARGS=()
build() {
  local dir="$1" sanitize="$2"
  shift 2
  local t0=$SECONDS
  # -O1: a fraction of -O2's compile time, fast enough to run; -g1: line tables, enough for the
  # reports' stacks and cheaper to compile than -g; no NDEBUG: assertions are checked.
  if ! cmake -S "$ROOT" -B "$dir" "${LAUNCHER[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
      -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" -DSTEREO_FUSION_SANITIZE="$sanitize" \
      -DCATKIN_ENABLE_TESTING=ON -DPYTHON_EXECUTABLE=/usr/bin/python3 -DPython3_EXECUTABLE=/usr/bin/python3 \
      "${BUILD_ARGS[@]}" >"$dir.configure.log" 2>&1; then
    cat "$dir.configure.log"
    return 1
  fi
  cmake --build "$dir" -j"$JOBS" $(printf -- '--target %s ' "$@") || return 1
  echo "[check] built $* with -fsanitize=$sanitize in $((SECONDS - t0)) s"
}

# run_rostests <name> <build dir> <ctest regex>: the rostests with every process of ours built
# with the sanitizers. The nodes' stderr reaches ctest's log (roslaunch leaves it on the console),
# and any report in it fails the step, even one printed while the launch shuts down.
run_rostests() {
  local name="$1" dir="$2" regex="$3" t0=$SECONDS status=clean logdir="$ROOT/.check-logs"
  mkdir -p "$logdir"
  STEREO_FUSION_MANAGER_PKG=stereo_fusion STEREO_FUSION_MANAGER_TYPE=stereo_fusion_manager \
    LSAN_OPTIONS="suppressions=$ROOT/test/lsan_suppressions.txt" \
    ctest --test-dir "$dir" -R "$regex" >"$logdir/$name.log" 2>&1 || status=FAILED
  cp "$dir/Testing/Temporary/LastTest.log" "$logdir/$name.output.log"
  local pattern='ERROR: (Address|Leak)Sanitizer|WARNING: ThreadSanitizer|runtime error:'
  local reports
  reports=$(grep -cE "$pattern" "$logdir/$name.output.log")
  if ((reports > 0)); then
    status="FAILED ($reports sanitizer reports)"
    grep -E -A30 "$pattern" "$logdir/$name.output.log" | head -n 120
  fi
  [ "$status" = clean ] || grep -E "Test +#|tests passed" "$logdir/$name.log"
  results+=("$name: $(grep -oE '[0-9]+% tests passed, [0-9]+ tests failed out of [0-9]+' "$logdir/$name.log" || echo 'no result'), $status ($((SECONDS - t0)) s; logs .check-logs/$name.*)")
  [ "$status" = clean ]
}

# The ROS targets the sanitizer runs of the rostests need.
ROS_TARGETS=(stereo_fusion_nodelet stereo_fusion_manager stereo_fusion_rostest stereo_fusion_assembler_test
             stereo_fusion_overload_test)
ROS_TESTS='_test_ros_(fusion_nodelet|mesh_assembler|overload)\.test$'

# run_gtest <name> <binary> <gtest filter>: runs the binary in $JOBS shards in parallel.
run_gtest() {
  local name="$1" binary="$2" filter="$3" t0=$SECONDS pids=() status=0 passed=0
  local logdir="$ROOT/.check-logs"
  mkdir -p "$logdir"
  for ((shard = 0; shard < JOBS; ++shard)); do
    GTEST_TOTAL_SHARDS="$JOBS" GTEST_SHARD_INDEX="$shard" "$binary" --gtest_filter="$filter" \
      >"$logdir/$name.$shard.log" 2>&1 &
    pids+=($!)
  done
  for ((shard = 0; shard < JOBS; ++shard)); do
    if ! wait "${pids[$shard]}"; then
      status=1
      echo "[check] $name shard $shard FAILED:"
      grep -E -A40 '^(==[0-9]+==ERROR|WARNING: ThreadSanitizer|SUMMARY: |.*runtime error:)|\[  FAILED  \]' \
        "$logdir/$name.$shard.log" | head -n 80
    fi
    passed=$((passed + $(grep -oE '^\[  PASSED  \] [0-9]+' "$logdir/$name.$shard.log" | grep -oE '[0-9]+$' || echo 0)))
  done
  results+=("$name: $passed tests passed, $( ((status)) && echo FAILED || echo clean ) ($((SECONDS - t0)) s; logs .check-logs/$name.*.log)")
  return $status
}

# The sanitizers' reports end the process with an error (-fno-sanitize-recover=all, halt_on_error).
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:strict_string_checks=1:detect_stack_use_after_return=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
export STEREO_FUSION_TEST_QUICK=1
export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$ROOT/test/tsan_suppressions.txt"

if [ "$mode" != --tsan ]; then
  # The core's unit tests in the standalone core build (cmake/core/, no catkin, no ROS): the
  # same build proves the core builds without ROS, so CI needs no second, plain one.
  t0=$SECONDS
  mkdir -p "$ROOT/.check-logs"
  core_log="$ROOT/.check-logs/asan_core_unit_tests.log"
  if CORE_SANITIZE=address,undefined CORE_BUILD_DIR="$ROOT/.build-core-asan" \
      "$ROOT/scripts/check_core_standalone.sh" >"$core_log" 2>&1; then
    results+=("asan_core_unit_tests: $(tail -n 1 "$core_log"), clean ($((SECONDS - t0)) s; log .check-logs/asan_core_unit_tests.log)")
  else
    failed=1
    grep -E -B2 -A40 '^(==[0-9]+==ERROR|SUMMARY: |.*runtime error:)|\[  FAILED  \]|core standalone:' "$core_log" | head -n 120
    results+=("asan_core_unit_tests: FAILED, $(tail -n 1 "$core_log") ($((SECONDS - t0)) s; log .check-logs/asan_core_unit_tests.log)")
  fi
  dir="$ROOT/.build-asan"
  # The tools, fuzz targets and ROS code link the core's objects from the build above rather than
  # compiling the core a second time with the same flags (cmake/core/prebuilt_core.cmake).
  BUILD_ARGS=(-DSTEREO_FUSION_PREBUILT_CORE=)
  if [ -f "$ROOT/.build-core-asan/core_built.stamp" ]; then  # built by this run (see there)
    BUILD_ARGS=(-DSTEREO_FUSION_PREBUILT_CORE="$ROOT/.build-core-asan")
  fi
  if build "$dir" address,undefined stereo_fusion_tool_tests stereo_fusion_fuzz_replays "${ROS_TARGETS[@]}"; then
    bin="$(find "$dir" -type f -name stereo_fusion_tool_tests -perm -u+x | head -n 1)"
    run_gtest asan_tool_tests "$bin" '*' || failed=1
    t0=$SECONDS
    replay_status=clean
    for replay in $(find "$dir" -type f -name 'fuzz_*_replay' -perm -u+x | sort); do
      target="$(basename "$replay" _replay)"
      if ! "$replay" "$ROOT/test/fuzz/corpus/$target" "$ROOT/test/fuzz/regressions/$target" \
          >"$ROOT/.check-logs/asan_$target.log" 2>&1; then
        replay_status=FAILED
        failed=1
        tail -n 40 "$ROOT/.check-logs/asan_$target.log"
      fi
      results+=("asan $target replay: $(tail -n 1 "$ROOT/.check-logs/asan_$target.log")")
    done
    results+=("asan fuzz replays: $replay_status ($((SECONDS - t0)) s)")
    run_rostests asan_ros "$dir" "$ROS_TESTS" || failed=1
  else
    results+=("asan build: FAILED"); failed=1
  fi
fi

if [ "$mode" != --asan ]; then
  dir="$ROOT/.build-tsan"
  BUILD_ARGS=(-DSTEREO_FUSION_PREBUILT_CORE=)
  if build "$dir" thread stereo_fusion_thread_tests "${ROS_TARGETS[@]}"; then
    bin="$(find "$dir" -type f -name stereo_fusion_thread_tests -perm -u+x | head -n 1)"
    threaded='ThreadPool.*:BlockOctree.ConcurrentAllocationCreatesEachBlockOnce'
    threaded+=':BlockOctreeLinks.EqualSearchesAfterRandomAllocateEraseClearSwap'
    threaded+=':BlockLookup.ResultDoesNotDependOnThreadsOrRegionSize:MapperProperties.ThreadCountDoesNotChangeTheMap'
    threaded+=':BlockMesher.ThreadCountDoesNotChangeTheMesh:PlanningScenes.QueriesWhileFusingAreSafe'
    threaded+=':MappingSession.EveryTrajectoryIsAccountedFor*:MappingSession.AResetDropsAWaitingTrajectory*'
    threaded+=':MappingSession.ARequestFindingTheMapBusy*'
    threaded+=':ContradictionFilter.DoesNotDependOnTheThreadCount:BlockOctree.CollectBlocksInParallelEqualsTheSerialWalk'
    threaded+=':PlanningMap.FramesFusedWhileAnUpdateFinishes*:MappingSession.ThePlanningUpdateLetsFramesIn*'
    threaded+=':MapperPaging.*:PageWriter.*'
    run_gtest tsan_thread_tests "$bin" "$threaded" || failed=1
    run_rostests tsan_ros "$dir" "$ROS_TESTS" || failed=1
  else
    results+=("tsan build: FAILED"); failed=1
  fi
fi

echo "[check] summary ($((SECONDS - start)) s):"
for line in "${results[@]}"; do echo "  $line"; done
if ((failed)); then echo "check: FAILED"; exit 1; fi
echo "check: clean"
