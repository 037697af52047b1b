// The fuser's --config and --set take the nodelet's YAML as it is: its own keys beside the mapping
// parameters. world_frame is the frame of a bag's poses (unless --world-frame), the other node
// keys are checked as the node checks them and ignored with a note; a name neither knows is an
// error naming the nearest known name.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "fuser/FuseArguments.h"
#include "fuser/OfflineFuser.h"

using namespace stereo_fusion;
namespace fs = std::filesystem;

namespace {

/// A YAML file in a fresh temporary folder, removed with the object.
struct YamlFile {
  explicit YamlFile(const std::string& text)
      : dir(fs::temp_directory_path() / ("stereo_fusion_fuse_args_" + std::to_string(::getpid()))) {
    fs::create_directories(dir);
    std::ofstream(path()) << text;
  }
  ~YamlFile() { fs::remove_all(dir); }
  std::string path() const { return (dir / "config.yaml").string(); }
  fs::path dir;
};

}  // namespace

TEST(FuseArguments, OneYamlServesTheNodeAndTheFuser) {
  const YamlFile yaml(
      "voxel_size_m: 0.03\n"
      "world_frame: odom\n"
      "queue_size: 12\n"
      "tf_timeout_s: 1.5\n");
  FuseOptions options;
  std::string error;
  ASSERT_TRUE(parseFuseArguments({"in.bag", "out", "--config", yaml.path()}, &options, &error))
      << error;
  EXPECT_EQ(options.config.voxel_size_m, 0.03);
  EXPECT_EQ(options.bag_topics.world_frame, "odom") << "the YAML's world_frame is the bag's frame";
  ASSERT_EQ(options.notes.size(), 1u);
  EXPECT_EQ(options.notes[0],
            yaml.path() + ": node parameters, ignored offline: queue_size, tf_timeout_s");

  // --world-frame wins over the file, wherever it stands.
  FuseOptions flagged;
  ASSERT_TRUE(parseFuseArguments({"--world-frame", "map", "in.bag", "out", "--config", yaml.path()},
                                 &flagged, &error))
      << error;
  EXPECT_EQ(flagged.bag_topics.world_frame, "map");

  // Without a world_frame anywhere: the node's default (REP 105's map).
  FuseOptions plain;
  ASSERT_TRUE(parseFuseArguments({"in.bag", "out"}, &plain, &error)) << error;
  EXPECT_EQ(plain.bag_topics.world_frame, "map");
  EXPECT_TRUE(plain.notes.empty());

  // --set takes the same keys.
  FuseOptions set;
  ASSERT_TRUE(parseFuseArguments(
      {"in.bag", "out", "--set", "world_frame=odom", "--set", "publish_markers=false"}, &set,
      &error))
      << error;
  EXPECT_EQ(set.bag_topics.world_frame, "odom");
  ASSERT_EQ(set.notes.size(), 1u);
  EXPECT_EQ(set.notes[0], "--set: node parameters, ignored offline: publish_markers");
}

TEST(FuseArguments, NodeKeysAreCheckedAndUnknownKeysNameTheNearestName) {
  std::string error;
  {  // A node key's value is checked as the node would check it.
    const YamlFile yaml("voxel_size_m: 0.03\nqueue_size: 0\n");
    FuseOptions options;
    EXPECT_FALSE(parseFuseArguments({"in.bag", "out", "--config", yaml.path()}, &options, &error));
    EXPECT_EQ(error, yaml.path() + ": parameter 'queue_size' = 0 is out of range [1, 1000] frames");
  }
  {  // A misspelt key: file, line, the key and the nearest name of either registry.
    const YamlFile yaml("voxel_size_m: 0.03\ntf_timout_s: 1\n");
    FuseOptions options;
    EXPECT_FALSE(parseFuseArguments({"in.bag", "out", "--config", yaml.path()}, &options, &error));
    EXPECT_EQ(error,
              yaml.path() + ":2: unknown parameter 'tf_timout_s' (did you mean 'tf_timeout_s'?)");
  }
  {
    FuseOptions options;
    EXPECT_FALSE(
        parseFuseArguments({"in.bag", "out", "--set", "voxel_size=0.02"}, &options, &error));
    EXPECT_EQ(error, "unknown parameter 'voxel_size' (did you mean 'voxel_size_m'?)");
    EXPECT_FALSE(parseFuseArguments({"in.bag", "out", "--set", "world_frame="}, &options, &error));
    EXPECT_EQ(error, "--set: parameter 'world_frame' must not be empty (a tf frame, not empty)");
  }
}
