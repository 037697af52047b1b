# The command lines of the tools (included from the root CMakeLists.txt). Only the tools link
# these; the core and the ROS layer have no command line.
#
#   stereo_fusion_cli                 CLI11 (header-only, Debian's libcli11-dev) and this folder's
#                                     helpers on it: exit codes (CommandLine.h), number checks
#   stereo_fusion_config_arguments    the mapping parameters' --config FILE and --set key=value
find_package(CLI11 CONFIG REQUIRED)
add_library(stereo_fusion_cli INTERFACE)
target_include_directories(stereo_fusion_cli INTERFACE ${PROJECT_SOURCE_DIR}/tools)
target_link_libraries(stereo_fusion_cli INTERFACE CLI11::CLI11)

add_library(stereo_fusion_config_arguments STATIC ${PROJECT_SOURCE_DIR}/tools/cli/MapperConfigArguments.cpp)
target_link_libraries(stereo_fusion_config_arguments PUBLIC stereo_fusion_cli stereo_fusion_core)
