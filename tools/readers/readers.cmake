# Readers only the tools and the tests use (included from the root CMakeLists.txt). Nothing in the
# core reads these formats, so they are not in stereo_fusion_core; the library is ROS-free.
#
#   PlyReader      PLY meshes: the evaluator's input; round trips of the core's PLY writer
#   ObjReader      OBJ + MTL (tinyobjloader): the texture comparison's input; round trips of the
#                  core's OBJ writer
#   DatasetReader  the dataset folder format described in DatasetReader.h (+ PFM, + OpenCV SGBM
#                  for a sequence with right/ images and no disparity/): input of the offline
#                  fuser, the evaluator and the texture comparison
add_library(stereo_fusion_readers STATIC
  ${PROJECT_SOURCE_DIR}/tools/readers/PlyReader.cpp
  ${PROJECT_SOURCE_DIR}/tools/readers/ObjReader.cpp
  ${PROJECT_SOURCE_DIR}/tools/readers/DatasetReader.cpp
)
target_include_directories(stereo_fusion_readers PUBLIC ${PROJECT_SOURCE_DIR}/tools)
find_package(tinyobjloader REQUIRED)  # Debian's libtinyobjloader-dev
target_link_libraries(stereo_fusion_readers PUBLIC stereo_fusion_core opencv_calib3d opencv_imgcodecs
                                                   opencv_imgproc yaml-cpp
                                            PRIVATE tinyobjloader::tinyobjloader)
