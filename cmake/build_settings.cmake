# Compiler settings shared by the catkin package (CMakeLists.txt) and the standalone build of the
# core (cmake/core/CMakeLists.txt), so both compile the core the same way.

# Release by default, portable (x86-64-v2) code; no host-specific flags in the default build.
if(NOT CMAKE_BUILD_TYPE AND NOT CMAKE_CONFIGURATION_TYPES)
  set(CMAKE_BUILD_TYPE Release CACHE STRING "Build type" FORCE)
endif()
set(CMAKE_CXX_STANDARD 17)
set(CMAKE_CXX_STANDARD_REQUIRED ON)
set(CMAKE_CXX_EXTENSIONS OFF)
set(CMAKE_CXX_FLAGS_RELEASE "-O3 -DNDEBUG -march=x86-64-v2")
set(CMAKE_POSITION_INDEPENDENT_CODE ON)
add_compile_options(-Wall -Wextra)
# STEREO_FUSION_SANITIZE / STEREO_FUSION_FUZZ (scripts/check.sh, scripts/fuzz.sh); off by default.
include(${CMAKE_CURRENT_LIST_DIR}/sanitizers.cmake)

# The tests' own code (test cases, scene set-up, message building) compiles at -O1 in Release: a
# third less compile time for the largest part of the build. The code under test is in the
# libraries and keeps -O3. Applied to the test executables by the catkin package and cmake/core/.
function(stereo_fusion_test_code)
  foreach(target ${ARGN})
    target_compile_options(${target} PRIVATE $<$<CONFIG:Release>:-O1>)
  endforeach()
endfunction()
