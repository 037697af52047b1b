# Targets of the stereo sequence simulator (owned by the simulator work; included from the root).

# Scenes, trajectories, stereo rendering and the dataset writer; the analytic primitives
# themselves are in stereo_fusion_sim (root CMakeLists.txt), shared with the tests and evaluator.
add_library(stereo_fusion_simulator STATIC
  tools/simulator/SceneLibrary.cpp
  tools/simulator/Trajectory.cpp
  tools/simulator/StereoRenderer.cpp
  tools/simulator/DatasetWriter.cpp
)
target_link_libraries(stereo_fusion_simulator PUBLIC stereo_fusion_sim stereo_fusion_readers ${OpenCV_LIBS})  # readers: SgbmParams

# scripts/simulate.sh runs this: writes a simulated sequence as a dataset folder.
add_executable(stereo_fusion_simulate tools/simulator/simulate_main.cpp tools/simulator/SimulateArguments.cpp)
target_link_libraries(stereo_fusion_simulate stereo_fusion_simulator stereo_fusion_ros stereo_fusion_cli)

if(CATKIN_ENABLE_TESTING)
  # test/unit/tools/test_simulator.cpp is globbed into the tools' unit test binary by the root.
  target_link_libraries(stereo_fusion_tool_tests stereo_fusion_simulator)
endif()
