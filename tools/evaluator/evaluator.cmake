# Targets of the mesh evaluator (owned by the evaluator work; included from the root).
#
#   stereo_fusion_evaluator   static library: PLY reading, exact mesh distances (BVH), surface
#                             sampling, ground-truth and held-out scoring, reports
#   stereo_fusion_evaluate    the command line tool behind scripts/evaluate.sh

set(EVALUATOR_DIR ${PROJECT_SOURCE_DIR}/tools/evaluator)

# The PLY reader belongs to the core library; until the core's source list holds it, the
# evaluator compiles it itself (either way it is compiled exactly once).
get_target_property(_evaluator_core_sources stereo_fusion_core SOURCES)
string(FIND "${_evaluator_core_sources}" "io/PlyReader.cpp" _evaluator_core_has_ply_reader)

set(EVALUATOR_SOURCES
  ${EVALUATOR_DIR}/TriangleDistance.cpp
  ${EVALUATOR_DIR}/TriangleBvh.cpp
  ${EVALUATOR_DIR}/BatchDistance.cpp
  ${EVALUATOR_DIR}/SurfaceSampler.cpp
  ${EVALUATOR_DIR}/DistanceStats.cpp
  ${EVALUATOR_DIR}/MeshEvaluator.cpp
  ${EVALUATOR_DIR}/SampleVisibility.cpp
  ${EVALUATOR_DIR}/DepthRasterizer.cpp
  ${EVALUATOR_DIR}/ResidualHistogram.cpp
  ${EVALUATOR_DIR}/HeldOutEvaluator.cpp
  ${EVALUATOR_DIR}/HeldOutSelection.cpp
  ${EVALUATOR_DIR}/EvaluateArguments.cpp
  ${EVALUATOR_DIR}/JsonWriter.cpp
  ${EVALUATOR_DIR}/EvaluationReport.cpp
)
if(_evaluator_core_has_ply_reader EQUAL -1)
  list(APPEND EVALUATOR_SOURCES ${PROJECT_SOURCE_DIR}/src/io/PlyReader.cpp)
endif()

add_library(stereo_fusion_evaluator STATIC ${EVALUATOR_SOURCES})
target_include_directories(stereo_fusion_evaluator PUBLIC ${PROJECT_SOURCE_DIR}/tools)
target_link_libraries(stereo_fusion_evaluator PUBLIC stereo_fusion_core)

add_executable(stereo_fusion_evaluate ${EVALUATOR_DIR}/evaluate_main.cpp)
target_link_libraries(stereo_fusion_evaluate stereo_fusion_evaluator)

if(CATKIN_ENABLE_TESTING)
  target_link_libraries(stereo_fusion_unit_tests stereo_fusion_evaluator)
endif()
