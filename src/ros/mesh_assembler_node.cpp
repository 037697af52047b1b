// Standalone node for a base station: loads stereo_fusion/MeshAssembler into this process.
#include <nodelet/loader.h>
#include <ros/ros.h>

int main(int argc, char** argv) {
  ros::init(argc, argv, "mesh_assembler");
  nodelet::Loader loader;
  nodelet::M_string remappings(ros::names::getRemappings());
  nodelet::V_string args(argv + 1, argv + argc);
  if (!loader.load(ros::this_node::getName(), "stereo_fusion/MeshAssembler", remappings, args)) {
    ROS_FATAL("mesh_assembler: could not load the nodelet (see the errors above)");
    return 1;
  }
  ros::spin();
  return 0;
}
