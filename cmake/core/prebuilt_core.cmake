# Imports stereo_fusion_core and stereo_fusion_sim from a build of cmake/core/ (the folder in
# STEREO_FUSION_PREBUILT_CORE), which exported them to stereo_fusion_core_targets.cmake. Objects
# compiled with other flags would link but mix two ABIs (a sanitizer's instrumentation on one side
# only), so the build type, its flags and the sanitizers must be the ones of this build.
set(_prebuilt ${STEREO_FUSION_PREBUILT_CORE})
if(NOT EXISTS ${_prebuilt}/stereo_fusion_core_targets.cmake)
  message(FATAL_ERROR "STEREO_FUSION_PREBUILT_CORE=${_prebuilt}: no stereo_fusion_core_targets.cmake "
                      "there; build cmake/core/ in that folder first (scripts/check_core_standalone.sh)")
endif()
# The cache's values, as both were configured (build_settings.cmake then sets Release's flags
# alike in both).
string(TOUPPER "${CMAKE_BUILD_TYPE}" _build_type)
set(_compared CMAKE_BUILD_TYPE STEREO_FUSION_SANITIZE STEREO_FUSION_FUZZ CMAKE_CXX_FLAGS
              CMAKE_CXX_FLAGS_${_build_type} CMAKE_CXX_COMPILER)
load_cache(${_prebuilt} READ_WITH_PREFIX _prebuilt_ ${_compared})
foreach(var ${_compared})
  if(NOT "${_prebuilt_${var}}" STREQUAL "$CACHE{${var}}")
    message(FATAL_ERROR "STEREO_FUSION_PREBUILT_CORE=${_prebuilt} was built with ${var}="
                        "'${_prebuilt_${var}}', this build has '$CACHE{${var}}'")
  endif()
endforeach()
include(${_prebuilt}/stereo_fusion_core_targets.cmake)
message(STATUS "stereo_fusion_core and stereo_fusion_sim: prebuilt in ${_prebuilt}")
