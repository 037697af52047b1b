# The soak run of scripts/soak.sh (included from the root CMakeLists.txt).
add_library(stereo_fusion_soak_lib STATIC tools/soak/SoakRun.cpp)
target_include_directories(stereo_fusion_soak_lib PUBLIC tools)
target_link_libraries(stereo_fusion_soak_lib PUBLIC stereo_fusion_core stereo_fusion_sim ${OpenCV_LIBS})
add_executable(stereo_fusion_soak tools/soak/soak_main.cpp)
target_link_libraries(stereo_fusion_soak stereo_fusion_soak_lib stereo_fusion_config_arguments)
