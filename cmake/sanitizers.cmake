# Sanitizer and fuzzing builds (scripts/check.sh, scripts/fuzz.sh). Included before any target
# is defined, so that every library a test or fuzz target links — the core above all — is
# instrumented the same way as the test itself; mixing instrumented and plain objects hides
# reports (ASan) or invents them (TSan).
#
#   -DSTEREO_FUSION_SANITIZE=address,undefined   (or thread; any -fsanitize= list)
#   -DSTEREO_FUSION_FUZZ=ON                      (clang: libFuzzer targets test/fuzz/fuzz_*.cpp)

set(STEREO_FUSION_SANITIZE "" CACHE STRING
    "Comma-separated -fsanitize= list for every target, e.g. address,undefined or thread; empty = none")
option(STEREO_FUSION_FUZZ "Build one libFuzzer executable per test/fuzz/fuzz_*.cpp (clang only)" OFF)

if(STEREO_FUSION_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    message(FATAL_ERROR "STEREO_FUSION_FUZZ needs clang (libFuzzer): configure with -DCMAKE_CXX_COMPILER=clang++-14")
  endif()
  # A fuzzer without ASan/UBSan only finds crashes; with them it finds the bugs behind them.
  if(NOT STEREO_FUSION_SANITIZE)
    set(STEREO_FUSION_SANITIZE "address,undefined")
  endif()
  # Coverage instrumentation for every object; only the fuzz executables link libFuzzer's main.
  add_compile_options(-fsanitize=fuzzer-no-link)
endif()

if(STEREO_FUSION_SANITIZE)
  # No recovery: a UBSan report must end the process with an error, or the test would pass.
  add_compile_options(-fsanitize=${STEREO_FUSION_SANITIZE} -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_link_options(-fsanitize=${STEREO_FUSION_SANITIZE})
  if(STEREO_FUSION_SANITIZE MATCHES "undefined" AND CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    add_compile_options(-fsanitize-ignorelist=${CMAKE_CURRENT_LIST_DIR}/ubsan_ignore.txt)
  endif()
  message(STATUS "stereo_fusion: sanitizers ${STEREO_FUSION_SANITIZE}")
endif()
