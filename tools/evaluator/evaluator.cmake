# Targets of the mesh evaluator (owned by the evaluator work; included from the root).
#
#   stereo_fusion_evaluator   static library: exact mesh distances (BVH), surface sampling,
#                             ground-truth and held-out scoring, reports, the error-coloured mesh,
#                             the ESDF's planning report (solid truth, occupancy map scores)
#   stereo_fusion_evaluate    the command line tool behind scripts/evaluate.sh (reads the PLY
#                             and the sequence with stereo_fusion_readers, tools/readers/)

set(EVALUATOR_DIR ${PROJECT_SOURCE_DIR}/tools/evaluator)

set(EVALUATOR_SOURCES
  ${EVALUATOR_DIR}/TriangleDistance.cpp
  ${EVALUATOR_DIR}/TriangleBvh.cpp
  ${EVALUATOR_DIR}/BatchDistance.cpp
  ${EVALUATOR_DIR}/SurfaceSampler.cpp
  ${EVALUATOR_DIR}/DistanceStats.cpp
  ${EVALUATOR_DIR}/MeshEvaluator.cpp
  ${EVALUATOR_DIR}/SampleVisibility.cpp
  ${EVALUATOR_DIR}/SeenTriangles.cpp
  ${EVALUATOR_DIR}/DepthRasterizer.cpp
  ${EVALUATOR_DIR}/ResidualHistogram.cpp
  ${EVALUATOR_DIR}/HeldOutEvaluator.cpp
  ${EVALUATOR_DIR}/HeldOutSelection.cpp
  ${EVALUATOR_DIR}/EvaluateArguments.cpp
  ${EVALUATOR_DIR}/EvaluationMode.cpp
  ${EVALUATOR_DIR}/EvaluationReport.cpp
  ${EVALUATOR_DIR}/ErrorColouredMesh.cpp
  ${EVALUATOR_DIR}/EsdfAccuracy.cpp
  ${EVALUATOR_DIR}/EsdfDelta.cpp
  ${EVALUATOR_DIR}/SolidTruth.cpp
  ${EVALUATOR_DIR}/PlanningScore.cpp
  ${EVALUATOR_DIR}/OccupancyMapFile.cpp
  ${EVALUATOR_DIR}/OccupancyScore.cpp
)

add_library(stereo_fusion_evaluator STATIC ${EVALUATOR_SOURCES})
target_include_directories(stereo_fusion_evaluator PUBLIC ${PROJECT_SOURCE_DIR}/tools)
target_link_libraries(stereo_fusion_evaluator PUBLIC stereo_fusion_core PRIVATE nlohmann_json::nlohmann_json
                                                                           stereo_fusion_cli)

add_executable(stereo_fusion_evaluate ${EVALUATOR_DIR}/evaluate_main.cpp)
target_link_libraries(stereo_fusion_evaluate stereo_fusion_evaluator stereo_fusion_readers stereo_fusion_cli)

# stereo_fusion_evaluate_esdf: an esdf.ply against the brute force (PCL's reader and exact k-d
# tree) and a ground-truth mesh.
find_package(PCL REQUIRED COMPONENTS common io kdtree)
add_executable(stereo_fusion_evaluate_esdf ${EVALUATOR_DIR}/esdf_main.cpp)
target_include_directories(stereo_fusion_evaluate_esdf SYSTEM PRIVATE ${PCL_INCLUDE_DIRS})
target_link_libraries(stereo_fusion_evaluate_esdf stereo_fusion_evaluator stereo_fusion_readers ${PCL_LIBRARIES}
                      nlohmann_json::nlohmann_json stereo_fusion_cli)

if(CATKIN_ENABLE_TESTING)
  target_link_libraries(stereo_fusion_tool_tests stereo_fusion_evaluator)
endif()
