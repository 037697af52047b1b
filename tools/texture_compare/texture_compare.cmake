# Textured vs vertex-coloured mesh against ground-truth images (scripts/texture_compare.sh).
#
#   stereo_fusion_texture_compare_lib   software rasteriser, image metrics, OBJ read back for rendering
#   stereo_fusion_texture_compare       the command line tool

add_library(stereo_fusion_texture_compare_lib STATIC
  ${PROJECT_SOURCE_DIR}/tools/texture_compare/MeshRasterizer.cpp
  ${PROJECT_SOURCE_DIR}/tools/texture_compare/ImageMetrics.cpp
  ${PROJECT_SOURCE_DIR}/tools/texture_compare/ObjRenderable.cpp
)
target_include_directories(stereo_fusion_texture_compare_lib PUBLIC ${PROJECT_SOURCE_DIR}/tools)
target_link_libraries(stereo_fusion_texture_compare_lib PUBLIC stereo_fusion_core stereo_fusion_readers)

add_executable(stereo_fusion_texture_compare ${PROJECT_SOURCE_DIR}/tools/texture_compare/texture_compare_main.cpp)
target_link_libraries(stereo_fusion_texture_compare stereo_fusion_texture_compare_lib stereo_fusion_offline
                      nlohmann_json::nlohmann_json)

if(CATKIN_ENABLE_TESTING)
  target_link_libraries(stereo_fusion_tool_tests stereo_fusion_texture_compare_lib)
endif()
