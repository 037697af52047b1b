# The unit tests that run code on several threads, in an executable of their own, so that the
# ThreadSanitizer build (scripts/check.sh --tsan) compiles only them and the core instead of
# every test, tool and the ROS layer. Not part of the normal build (the same tests are in
# stereo_fusion_unit_tests). A new threaded test in another file: add the file here.
if(CATKIN_ENABLE_TESTING)
  add_executable(stereo_fusion_thread_tests EXCLUDE_FROM_ALL
    ${PROJECT_SOURCE_DIR}/test/unit/util/test_thread_pool.cpp
    ${PROJECT_SOURCE_DIR}/test/unit/map/test_octree.cpp
    ${PROJECT_SOURCE_DIR}/test/unit/map/test_octree_links.cpp
    ${PROJECT_SOURCE_DIR}/test/unit/integration/test_lookup.cpp
    ${PROJECT_SOURCE_DIR}/test/unit/integration/test_contradiction_filter.cpp
    ${PROJECT_SOURCE_DIR}/test/unit/mapper/test_mapper_properties.cpp
    ${PROJECT_SOURCE_DIR}/test/unit/mesh/test_block_mesher.cpp
    ${PROJECT_SOURCE_DIR}/test/unit/planning/test_planning_scenes.cpp
    ${PROJECT_SOURCE_DIR}/test/unit/session/test_mapping_session.cpp
    ${PROJECT_SOURCE_DIR}/test/unit/mapper/test_mapper_paging.cpp  # the page writer's thread
    ${PROJECT_SOURCE_DIR}/test/unit/paging/test_page_writer.cpp
    ${PROJECT_SOURCE_DIR}/test/tsan/OpenCvSerial.cpp  # TSan cannot see TBB's synchronisation
  )
  target_include_directories(stereo_fusion_thread_tests PRIVATE ${PROJECT_SOURCE_DIR}/test/unit)
  target_link_libraries(stereo_fusion_thread_tests stereo_fusion_core stereo_fusion_sim
                        GTest::gtest GTest::gtest_main)
endif()
