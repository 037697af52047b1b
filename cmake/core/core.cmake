# The core: stereo_fusion_core, the ROS-free library (everything in src/ and include/ outside
# ros/), and its unit tests. Included by the catkin package (CMakeLists.txt) and by the plain CMake
# project next to this file (cmake/core/CMakeLists.txt, built and tested alone by
# scripts/check_core_standalone.sh in CI), so the core cannot come to need catkin, ROS, rosbag or
# a tool without that build failing.
#
# The includer sets STEREO_FUSION_ROOT (the repository) and STEREO_FUSION_CORE_TESTS, and has found
# Eigen3, OpenCV (core imgproc imgcodecs calib3d), yaml-cpp, Threads, ZLIB, SQLite3 and zstd; with the tests also GTest
# and include(GoogleTest).
#
#   stereo_fusion_core         the library
#   stereo_fusion_sim          analytic scenes and ray casting (tools/simulator/AnalyticScene.cpp, no
#                              ROS): ground truth for the tests, the simulator and the evaluator
#   stereo_fusion_unit_tests   the core's unit tests, test/unit/<folder>/ for every core folder
#                              below; they link the two libraries above and GTest, nothing else
#                              (the tools' and the ROS layer's unit tests are stereo_fusion_tool_tests,
#                              defined by the catkin package)

# The core's unit tests live in test/unit/<folder>/ for these folders (the catkin package checks
# that every test folder belongs to the core or to the tools).
set(STEREO_FUSION_CORE_TEST_FOLDERS camera map integration mesh io util mapper trajectory planning session layers paging)

# STEREO_FUSION_PREBUILT_CORE=<build dir of cmake/core/>: take stereo_fusion_core and
# stereo_fusion_sim from that build instead of compiling them again (scripts/check.sh's ASan step:
# the standalone core build runs the core's tests, the catkin build links the same objects into
# the tools and the nodelet). Both builds must use the same build type, flags and sanitizers.
if(STEREO_FUSION_PREBUILT_CORE)
  include(${CMAKE_CURRENT_LIST_DIR}/prebuilt_core.cmake)
  return()
endif()

add_library(stereo_fusion_core STATIC
  ${STEREO_FUSION_ROOT}/src/ParameterTable.cpp
  ${STEREO_FUSION_ROOT}/src/MapperConfig.cpp
  ${STEREO_FUSION_ROOT}/src/Mapper.cpp
  ${STEREO_FUSION_ROOT}/src/MapperCheckpoint.cpp
  ${STEREO_FUSION_ROOT}/src/MapperPaging.cpp
  ${STEREO_FUSION_ROOT}/src/paging/BlockPage.cpp
  ${STEREO_FUSION_ROOT}/src/paging/BlockStore.cpp
  ${STEREO_FUSION_ROOT}/src/paging/CheckpointState.cpp
  ${STEREO_FUSION_ROOT}/src/paging/FrameReach.cpp
  ${STEREO_FUSION_ROOT}/src/paging/PagedBlocks.cpp
  ${STEREO_FUSION_ROOT}/src/paging/PageWriter.cpp
  ${STEREO_FUSION_ROOT}/src/StageConfigs.cpp
  ${STEREO_FUSION_ROOT}/src/layers/MeshLayer.cpp
  ${STEREO_FUSION_ROOT}/src/layers/PlanningLayer.cpp
  ${STEREO_FUSION_ROOT}/src/camera/StereoCamera.cpp
  ${STEREO_FUSION_ROOT}/src/camera/DepthToDisparity.cpp
  ${STEREO_FUSION_ROOT}/src/map/BlockOctree.cpp
  ${STEREO_FUSION_ROOT}/src/map/VoxelBlock.cpp
  ${STEREO_FUSION_ROOT}/src/map/BlockChangeLog.cpp
  ${STEREO_FUSION_ROOT}/src/map/EvictionPolicy.cpp
  ${STEREO_FUSION_ROOT}/src/map/MapRegion.cpp
  ${STEREO_FUSION_ROOT}/src/map/RegionClearing.cpp
  ${STEREO_FUSION_ROOT}/src/trajectory/PoseCorrection.cpp
  ${STEREO_FUSION_ROOT}/src/trajectory/UnitQuaternion.cpp
  ${STEREO_FUSION_ROOT}/src/session/CorrectionWorker.cpp
  ${STEREO_FUSION_ROOT}/src/session/EditReplay.cpp
  ${STEREO_FUSION_ROOT}/src/session/EditTimeline.cpp
  ${STEREO_FUSION_ROOT}/src/session/FrameStats.cpp
  ${STEREO_FUSION_ROOT}/src/session/InputHealth.cpp
  ${STEREO_FUSION_ROOT}/src/session/MappingSession.cpp
  ${STEREO_FUSION_ROOT}/src/session/OutputCadence.cpp
  ${STEREO_FUSION_ROOT}/src/session/TrajectoryOutcome.cpp
  ${STEREO_FUSION_ROOT}/src/integration/StereoFrame.cpp
  ${STEREO_FUSION_ROOT}/src/integration/FrameGate.cpp
  ${STEREO_FUSION_ROOT}/src/integration/FramePipeline.cpp
  ${STEREO_FUSION_ROOT}/src/integration/RejectReason.cpp
  ${STEREO_FUSION_ROOT}/src/integration/BlockLookup.cpp
  ${STEREO_FUSION_ROOT}/src/integration/BlockLookupRun.cpp
  ${STEREO_FUSION_ROOT}/src/integration/SurfaceFuser.cpp
  ${STEREO_FUSION_ROOT}/src/integration/FreeSpaceCarver.cpp
  ${STEREO_FUSION_ROOT}/src/integration/MeasurementImage.cpp
  ${STEREO_FUSION_ROOT}/src/integration/DisparityCoherence.cpp
  ${STEREO_FUSION_ROOT}/src/integration/OutlierRejection.cpp
  ${STEREO_FUSION_ROOT}/src/integration/ContradictionFilter.cpp
  ${STEREO_FUSION_ROOT}/src/integration/DisparityNoise.cpp
  ${STEREO_FUSION_ROOT}/src/integration/LevelSelection.cpp
  ${STEREO_FUSION_ROOT}/src/integration/DepthTiles.cpp
  ${STEREO_FUSION_ROOT}/src/integration/FusionKernels.cpp
  ${STEREO_FUSION_ROOT}/src/integration/FusionKernelsAvx2.cpp
  ${STEREO_FUSION_ROOT}/src/mesh/CellPolygonizer.cpp
  ${STEREO_FUSION_ROOT}/src/mesh/BlockMesher.cpp
  ${STEREO_FUSION_ROOT}/src/mesh/MesherContext.cpp
  ${STEREO_FUSION_ROOT}/src/mesh/MesherGeneralPath.cpp
  ${STEREO_FUSION_ROOT}/src/mesh/MesherMixedPath.cpp
  ${STEREO_FUSION_ROOT}/src/mesh/MesherSampling.cpp
  ${STEREO_FUSION_ROOT}/src/mesh/MesherTables.cpp
  ${STEREO_FUSION_ROOT}/src/mesh/MesherUniformPath.cpp
  ${STEREO_FUSION_ROOT}/src/mesh/VertexNormals.cpp
  ${STEREO_FUSION_ROOT}/src/mesh/MeshLevel.cpp
  ${STEREO_FUSION_ROOT}/src/mesh/MeshStore.cpp
  ${STEREO_FUSION_ROOT}/src/mesh/TexturePatch.cpp
  ${STEREO_FUSION_ROOT}/src/mesh/TextureStore.cpp
  ${STEREO_FUSION_ROOT}/src/planning/TsdfOccupancy.cpp
  ${STEREO_FUSION_ROOT}/src/planning/FreeSpaceRecorder.cpp
  ${STEREO_FUSION_ROOT}/src/planning/EsdfPropagator.cpp
  ${STEREO_FUSION_ROOT}/src/planning/EsdfTransit.cpp
  ${STEREO_FUSION_ROOT}/src/planning/PlanningMap.cpp
  ${STEREO_FUSION_ROOT}/src/planning/PlanningMapQueries.cpp
  ${STEREO_FUSION_ROOT}/src/planning/OccupancyGrid2D.cpp
  ${STEREO_FUSION_ROOT}/src/planning/FleetGridMerge.cpp
  ${STEREO_FUSION_ROOT}/src/planning/GridPatch.cpp
  ${STEREO_FUSION_ROOT}/src/io/PlanningExport.cpp
  ${STEREO_FUSION_ROOT}/src/io/TextureAtlas.cpp
  ${STEREO_FUSION_ROOT}/src/io/MeshExport.cpp
  ${STEREO_FUSION_ROOT}/src/io/OperatorMeshExport.cpp
  ${STEREO_FUSION_ROOT}/src/io/ObjWriter.cpp
  ${STEREO_FUSION_ROOT}/src/io/ConfigFile.cpp
  ${STEREO_FUSION_ROOT}/src/io/PlyWriter.cpp
  ${STEREO_FUSION_ROOT}/src/io/MapFile.cpp
  ${STEREO_FUSION_ROOT}/src/io/MapFileWrite.cpp
  ${STEREO_FUSION_ROOT}/src/io/WriteTarget.cpp
  ${STEREO_FUSION_ROOT}/src/util/ThreadPool.cpp
  ${STEREO_FUSION_ROOT}/src/util/Crc32.cpp
  ${STEREO_FUSION_ROOT}/src/util/CpuFeatures.cpp
  ${STEREO_FUSION_ROOT}/src/util/ProcessMemory.cpp
)
target_include_directories(stereo_fusion_core PUBLIC ${STEREO_FUSION_ROOT}/include ${EIGEN3_INCLUDE_DIR}
                                                     ${OpenCV_INCLUDE_DIRS})
# The OpenCV modules the core uses (the includer may have found more for the tools).
target_link_libraries(stereo_fusion_core PUBLIC opencv_core opencv_imgproc opencv_imgcodecs opencv_calib3d yaml-cpp
                                                Threads::Threads ZLIB::ZLIB SQLite::SQLite3 zstd::libzstd_shared)

# Analytic scenes and ray casting: ground truth for tests, the simulator and the evaluator.
add_library(stereo_fusion_sim STATIC ${STEREO_FUSION_ROOT}/tools/simulator/AnalyticScene.cpp)
target_include_directories(stereo_fusion_sim PUBLIC ${STEREO_FUSION_ROOT}/tools)
target_link_libraries(stereo_fusion_sim PUBLIC stereo_fusion_core)

# The core's unit tests: one gtest binary (one link, parallel compile); every test case is its own
# ctest entry so the summary counts cases. The helpers (TestSupport.h, ...) are in test/unit/.
if(STEREO_FUSION_CORE_TESTS)
  set(_core_test_globs)
  foreach(folder ${STEREO_FUSION_CORE_TEST_FOLDERS})
    list(APPEND _core_test_globs ${STEREO_FUSION_ROOT}/test/unit/${folder}/*.cpp)
  endforeach()
  file(GLOB STEREO_FUSION_CORE_TEST_SOURCES CONFIGURE_DEPENDS ${_core_test_globs})
  add_executable(stereo_fusion_unit_tests ${STEREO_FUSION_CORE_TEST_SOURCES})
  target_include_directories(stereo_fusion_unit_tests PRIVATE ${STEREO_FUSION_ROOT}/test/unit)
  target_link_libraries(stereo_fusion_unit_tests stereo_fusion_core stereo_fusion_sim GTest::gtest GTest::gtest_main)
  target_compile_definitions(stereo_fusion_unit_tests PRIVATE STEREO_FUSION_SOURCE_DIR="${STEREO_FUSION_ROOT}")
  stereo_fusion_test_code(stereo_fusion_unit_tests)
  # A test's time limit; sanitizers run the code 2-15x slower (scripts/check.sh).
  set(_core_test_timeout_s 300)
  if(STEREO_FUSION_SANITIZE)
    set(_core_test_timeout_s 1200)
  endif()
  gtest_discover_tests(stereo_fusion_unit_tests DISCOVERY_TIMEOUT 60
                       PROPERTIES TIMEOUT ${_core_test_timeout_s})
endif()
