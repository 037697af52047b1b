// Standalone node: loads stereo_fusion/FusionNodelet into this process (no nodelet manager).
#include <nodelet/loader.h>
#include <ros/ros.h>

int main(int argc, char** argv) {
  ros::init(argc, argv, "stereo_fusion");
  nodelet::Loader loader;
  nodelet::M_string remappings(ros::names::getRemappings());
  nodelet::V_string args(argv + 1, argv + argc);
  if (!loader.load(ros::this_node::getName(), "stereo_fusion/FusionNodelet", remappings, args)) {
    ROS_FATAL("stereo_fusion: could not load the nodelet (see the errors above)");
    return 1;
  }
  ros::spin();
  return 0;
}
