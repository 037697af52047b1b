// The node parameter registry (src/ros/RosParameters.cpp) without a master: its defaults are
// NodeConfig's and valid, every value reads back as it was set, invalid values are refused with
// the parameter's name, range and unit, its names do not collide with the mapping parameters'
// (loadParameters reads both from one namespace), and the launch files' arguments named after a
// node parameter default to the registry's default. loadParameters against a real master:
// rostest NodeParameters.* (test/ros/test_fusion_nodelet.cpp).
#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include "stereo_fusion/ros/RosParameters.h"

using namespace stereo_fusion;

namespace {

const std::string kSourceDir = STEREO_FUSION_SOURCE_DIR;

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

TEST(NodeParameterRegistry, DefaultsAreNodeConfigsAndValid) {
  const NodeConfig defaults;
  EXPECT_TRUE(validateNodeConfig(defaults).empty());
  EXPECT_EQ(getNodeParameter(defaults, "world_frame"), "map");
  EXPECT_EQ(getNodeParameter(defaults, "input"), "disparity");
  EXPECT_EQ(getNodeParameter(defaults, "depth_baseline_m"), "0.05");
  EXPECT_EQ(getNodeParameter(defaults, "image_transport"), "raw");
  EXPECT_EQ(getNodeParameter(defaults, "depth_image_transport"), "raw");
  EXPECT_EQ(getNodeParameter(defaults, "queue_size"), "5");
  EXPECT_EQ(getNodeParameter(defaults, "queue_policy"), "drop_oldest");
  EXPECT_EQ(getNodeParameter(defaults, "tf_timeout_s"), "0.2");
  EXPECT_EQ(getNodeParameter(defaults, "mesh_encoding"), "float32");
  EXPECT_EQ(getNodeParameter(defaults, "trajectory_frame"), "");
  EXPECT_EQ(getNodeParameter(defaults, "max_request_wait_s"), "2");
  EXPECT_EQ(getNodeParameter(defaults, "diagnostics_window_s"), "10");
  EXPECT_EQ(getNodeParameter(defaults, "input_timeout_s"), "2");
  EXPECT_EQ(getNodeParameter(defaults, "allow_unknown_parameters"), "false");
  EXPECT_EQ(getNodeParameter(defaults, "no_such_parameter"), "");
  // Every field of NodeConfig has its one definition (drop_oldest is queue_policy).
  std::vector<std::string> names;
  for (const ParameterSpec& spec : nodeParameterSpecs()) names.push_back(spec.name);
  EXPECT_EQ(names, (std::vector<std::string>{"world_frame",
                                             "input",
                                             "depth_baseline_m",
                                             "image_transport",
                                             "depth_image_transport",
                                             "queue_size",
                                             "queue_policy",
                                             "approximate_sync",
                                             "sync_queue_size",
                                             "tf_timeout_s",
                                             "max_stamp_ahead_s",
                                             "mesh_publish_rate_hz",
                                             "publish_markers",
                                             "markers_publish_rate_hz",
                                             "publish_path",
                                             "publish_frustum",
                                             "frustum_depth_m",
                                             "publish_block_bounds",
                                             "mesh_encoding",
                                             "loop_closure_max_frames",
                                             "trajectory_frame",
                                             "planning_publish_rate_hz",
                                             "esdf_slice_height_m",
                                             "planning_max_box_cells",
                                             "planning_max_query_points",
                                             "max_request_wait_s",
                                             "diagnostics_window_s",
                                             "input_timeout_s",
                                             "allow_unknown_parameters"}));
  for (const ParameterSpec& spec : nodeParameterSpecs()) {
    EXPECT_FALSE(spec.description.empty()) << spec.name;
    EXPECT_FALSE(spec.range.empty()) << spec.name;
    // The default reads back through the setter unchanged.
    NodeConfig parsed;
    std::string error;
    ASSERT_TRUE(setNodeParameter(&parsed, spec.name, getNodeParameter(defaults, spec.name), &error))
        << error;
    EXPECT_EQ(getNodeParameter(parsed, spec.name), getNodeParameter(defaults, spec.name))
        << spec.name;
  }
}

TEST(NodeParameterRegistry, SetsEveryTypeIntoTheFieldsTheNodeletReads) {
  NodeConfig c;
  std::string error;
  for (const auto& [name, value] :
       std::vector<std::pair<std::string, std::string>>{{"world_frame", "map"},
                                                        {"queue_size", "12"},
                                                        {"queue_policy", "drop_newest"},
                                                        {"approximate_sync", "true"},
                                                        {"sync_queue_size", "3"},
                                                        {"tf_timeout_s", "1.5"},
                                                        {"max_stamp_ahead_s", "0"},
                                                        {"mesh_publish_rate_hz", "0.5"},
                                                        {"publish_markers", "false"},
                                                        {"publish_path", "0"},
                                                        {"publish_frustum", "false"},
                                                        {"frustum_depth_m", "2.5"},
                                                        {"publish_block_bounds", "true"},
                                                        {"mesh_encoding", "compact"},
                                                        {"loop_closure_max_frames", "0"},
                                                        {"trajectory_frame", "base_link"},
                                                        {"max_request_wait_s", "0.5"},
                                                        {"allow_unknown_parameters", "true"}}) {
    ASSERT_TRUE(setNodeParameter(&c, name, value, &error)) << name << ": " << error;
  }
  EXPECT_EQ(c.world_frame, "map");
  EXPECT_EQ(c.queue_size, 12);
  EXPECT_FALSE(c.drop_oldest);
  EXPECT_TRUE(c.approximate_sync);
  EXPECT_EQ(c.sync_queue_size, 3);
  EXPECT_EQ(c.tf_timeout_s, 1.5);
  EXPECT_EQ(c.max_stamp_ahead_s, 0.0);
  EXPECT_EQ(c.mesh_publish_rate_hz, 0.5);
  EXPECT_FALSE(c.publish_markers);
  EXPECT_FALSE(c.publish_path);
  EXPECT_FALSE(c.publish_frustum);
  EXPECT_EQ(c.frustum_depth_m, 2.5);
  EXPECT_TRUE(c.publish_block_bounds);
  EXPECT_EQ(c.mesh_encoding, MeshEncoding::kCompact);
  EXPECT_EQ(c.loop_closure_max_frames, 0);
  EXPECT_EQ(c.trajectory_frame, "base_link");
  EXPECT_EQ(c.max_request_wait_s, 0.5);
  EXPECT_TRUE(c.allow_unknown_parameters);
  EXPECT_TRUE(validateNodeConfig(c).empty());
  EXPECT_TRUE(setNodeParameter(&c, "trajectory_frame", "", &error)) << "empty = the camera frame";
}

TEST(NodeParameterRegistry, InvalidValuesAreRefusedNamingParameterRangeAndUnit) {
  struct Case {
    const char* name;
    const char* value;
    const char* message;
  };
  const std::vector<Case> cases = {
      {"queue_size", "-3", "parameter 'queue_size' = -3 is out of range [1, 1000] frames"},
      {"queue_size", "0", "parameter 'queue_size' = 0 is out of range [1, 1000] frames"},
      {"queue_size", "2.5", "parameter 'queue_size': '2.5' is not an integer"},
      {"queue_policy", "drop_all",
       "parameter 'queue_policy': 'drop_all' is not one of drop_oldest | drop_newest"},
      {"approximate_sync", "sometimes",
       "parameter 'approximate_sync': 'sometimes' is not true or false"},
      {"sync_queue_size", "1001",
       "parameter 'sync_queue_size' = 1001 is out of range [1, 1000] messages"},
      {"tf_timeout_s", "-1", "parameter 'tf_timeout_s' = -1 is out of range [0, 10] s"},
      {"tf_timeout_s", "nan", "parameter 'tf_timeout_s': 'nan' is not a finite number"},
      {"max_stamp_ahead_s", "2e6",
       "parameter 'max_stamp_ahead_s' = 2e6 is out of range [0, 1e+06] s"},
      {"mesh_publish_rate_hz", "-2",
       "parameter 'mesh_publish_rate_hz' = -2 is out of range [0, 1000] Hz"},
      {"frustum_depth_m", "0", "parameter 'frustum_depth_m' = 0 is out of range (0, 100] m"},
      {"mesh_encoding", "float16",
       "parameter 'mesh_encoding': 'float16' is not one of float32 | compact"},
      {"loop_closure_max_frames", "-1",
       "parameter 'loop_closure_max_frames' = -1 is out of range [0, 100000] frames"},
      {"world_frame", "", "parameter 'world_frame' must not be empty (a tf frame, not empty)"},
      {"publish_path", "yes", "parameter 'publish_path': 'yes' is not true or false"},
      {"max_request_wait_s", "0", "parameter 'max_request_wait_s' = 0 is out of range (0, 60] s"},
      {"max_request_wait_s", "61", "parameter 'max_request_wait_s' = 61 is out of range (0, 60] s"},
      {"diagnostics_window_s", "0",
       "parameter 'diagnostics_window_s' = 0 is out of range (0, 3600] s"},
      {"input_timeout_s", "-1", "parameter 'input_timeout_s' = -1 is out of range [0, 3600] s"},
      {"input_timeout_s", "inf", "parameter 'input_timeout_s': 'inf' is not a finite number"},
      {"allow_unknown_parameters", "maybe",
       "parameter 'allow_unknown_parameters': 'maybe' is not true or false"},
      {"queue_length", "5", "unknown parameter 'queue_length' (did you mean 'queue_size'?)"},
  };
  for (const Case& c : cases) {
    NodeConfig config;
    std::string error;
    EXPECT_FALSE(setNodeParameter(&config, c.name, c.value, &error)) << c.name << " = " << c.value;
    EXPECT_EQ(error, c.message);
    EXPECT_EQ(getNodeParameter(config, c.name), getNodeParameter(NodeConfig{}, c.name))
        << "a refused value changes nothing";
  }
  NodeConfig bad;
  bad.queue_size = -1;
  bad.frustum_depth_m = 0.0;
  bad.world_frame.clear();
  EXPECT_EQ(
      validateNodeConfig(bad),
      (std::vector<std::string>{"parameter 'world_frame' must not be empty (a tf frame, not empty)",
                                "parameter 'queue_size' = -1 is out of range [1, 1000] frames",
                                "parameter 'frustum_depth_m' = 0 is out of range (0, 100] m"}));
}

// loadParameters() reads both registries from one private namespace: a name in both would be
// read twice, as two different parameters.
TEST(NodeParameterRegistry, NamesAreDistinctFromTheMappingParameters) {
  std::set<std::string> mapping;
  for (const ParameterSpec& spec : mapperParameterSpecs()) mapping.insert(spec.name);
  for (const ParameterSpec& spec : nodeParameterSpecs())
    EXPECT_EQ(mapping.count(spec.name), 0u) << spec.name;
  // The names loadParameters() lets other code keep in the namespace are no parameter of ours.
  for (const std::string& name : foreignNodeParameterNames()) {
    EXPECT_EQ(mapping.count(name), 0u) << name;
    EXPECT_TRUE(getNodeParameter(NodeConfig{}, name).empty()) << name;
  }
}

// Every launch file takes world_frame, empty by default: empty leaves the config's world_frame
// (or the node's default) alone, so fusion.launch sets the parameter only when the argument is
// given. Any other <arg> named after a node parameter would set it, so its default must be the
// registry's. config/default.yaml holds the mapping parameters only (the node's keep the
// registry's defaults; the offline fuser accepts and ignores them in a --config file). Whether a
// world_frame in a YAML survives fusion.launch: rostest replay_odom_yaml.test.
TEST(NodeParameterRegistry, LaunchFilesTakeWorldFrameAndKeepTheConfigs) {
  const NodeConfig defaults;
  const std::regex arg_default(R"re(<arg\s+name="([A-Za-z0-9_]+)"\s+default="([^"]*)")re");
  for (const char* launch : {"fusion.launch", "stereo_pipeline.launch", "replay.launch",
                             "rviz.launch", "base_station.launch"}) {
    const std::string text = readFile(kSourceDir + "/launch/" + launch);
    ASSERT_FALSE(text.empty()) << launch;
    EXPECT_NE(text.find("<arg name=\"world_frame\" default=\"\"/>"), std::string::npos)
        << launch << ": <arg name=\"world_frame\" default=\"\"/>";
    for (std::sregex_iterator it(text.begin(), text.end(), arg_default), end; it != end; ++it) {
      const std::string name = (*it)[1];
      if (name == "world_frame") continue;
      for (const ParameterSpec& spec : nodeParameterSpecs())
        if (spec.name == name)
          EXPECT_EQ((*it)[2].str(), getNodeParameter(defaults, name))
              << launch << ": <arg name=\"" << name << "\">";
    }
  }
  const std::string fusion = readFile(kSourceDir + "/launch/fusion.launch");
  EXPECT_NE(fusion.find("<param unless=\"$(eval arg('world_frame') == '')\" name=\"world_frame\""),
            std::string::npos)
      << "fusion.launch must not overwrite a config's world_frame with an empty argument";
  const std::string yaml = readFile(kSourceDir + "/config/default.yaml");
  ASSERT_FALSE(yaml.empty());
  for (const ParameterSpec& spec : nodeParameterSpecs())
    EXPECT_EQ(yaml.find("\n" + spec.name + ":"), std::string::npos)
        << spec.name << " in config/default.yaml";
}
