# Fuzz targets: every test/fuzz/fuzz_<name>.cpp defines LLVMFuzzerTestOneInput and becomes
#   - with STEREO_FUSION_FUZZ (clang):  the libFuzzer executable fuzz_<name>  (scripts/fuzz.sh)
#   - in the normal test build:         fuzz_<name>_replay, run by ctest over the checked-in
#                                       corpus/fuzz_<name>/ and regressions/fuzz_<name>/
# A new file is picked up by the glob; no edit here is needed. Targets link stereo_fusion_core and
# stereo_fusion_readers (the dataset folder and PFM readers, tools/readers/); fuzz_ros_<name>
# targets also the ROS layer's message code (stereo_fusion_nodelet, the generated messages).

set(FUZZ_DIR ${PROJECT_SOURCE_DIR}/test/fuzz)
file(GLOB FUZZ_TARGET_SOURCES CONFIGURE_DEPENDS ${FUZZ_DIR}/fuzz_*.cpp)
list(REMOVE_ITEM FUZZ_TARGET_SOURCES ${FUZZ_DIR}/fuzz_replay_main.cpp)

function(stereo_fusion_fuzz_ros_deps target)
  if(target MATCHES "^fuzz_ros_")
    target_link_libraries(${target} stereo_fusion_nodelet)
    add_dependencies(${target} ${PROJECT_NAME}_generate_messages_cpp)
  endif()
endfunction()

if(STEREO_FUSION_FUZZ)
  foreach(source ${FUZZ_TARGET_SOURCES})
    get_filename_component(name ${source} NAME_WE)
    add_executable(${name} ${source})
    target_link_libraries(${name} stereo_fusion_core stereo_fusion_readers)
    stereo_fusion_fuzz_ros_deps(${name})
    target_link_options(${name} PRIVATE -fsanitize=fuzzer)
  endforeach()
elseif(CATKIN_ENABLE_TESTING)
  add_custom_target(stereo_fusion_fuzz_replays)
  foreach(source ${FUZZ_TARGET_SOURCES})
    get_filename_component(name ${source} NAME_WE)
    add_executable(${name}_replay ${source} ${FUZZ_DIR}/fuzz_replay_main.cpp)
    target_link_libraries(${name}_replay stereo_fusion_core stereo_fusion_readers)
    stereo_fusion_fuzz_ros_deps(${name}_replay)
    add_dependencies(stereo_fusion_fuzz_replays ${name}_replay)
    add_test(NAME fuzz_replay.${name}
             COMMAND ${name}_replay ${FUZZ_DIR}/corpus/${name} ${FUZZ_DIR}/regressions/${name})
    set_tests_properties(fuzz_replay.${name} PROPERTIES TIMEOUT 300)
  endforeach()
endif()
