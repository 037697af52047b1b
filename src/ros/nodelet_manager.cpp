// A nodelet manager (what `rosrun nodelet nodelet manager` runs) built with this package's
// compiler flags. Sanitizer runs (scripts/check.sh --asan / --tsan) start it instead of nodelet's
// own, so that the instrumented nodelets are loaded into a process whose sanitizer runtime comes
// first.
#include <nodelet/loader.h>
#include <ros/ros.h>

int main(int argc, char** argv) {
  ros::init(argc, argv, "manager");
  nodelet::Loader manager(true);  // load_nodelet / unload_nodelet / list services
  ros::spin();
  return 0;
}
