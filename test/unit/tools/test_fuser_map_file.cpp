// The offline fuser's --save-map / --load-map (the map file itself:
// test/unit/io/test_map_file.cpp).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>

#include "MeshTestSupport.h"
#include "fuser/FuseArguments.h"
#include "fuser/OfflineFuser.h"
#include "simulator/DatasetWriter.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;
namespace fs = std::filesystem;

namespace {}  // namespace

TEST(OfflineFuser, SaveMapThenLoadMapAloneWritesTheSameMesh) {
  const fs::path seq =
      fs::path(testing::TempDir()) / ("stereo_fusion_mapfile_seq_" + std::to_string(::getpid()));
  fs::remove_all(seq);
  std::string error;
  auto writer = sim::DatasetWriter::create(seq.string(), qvgaCamera(), &error);
  ASSERT_TRUE(writer) << error;
  const sim::AnalyticScene scene = floorAndSphere();
  for (int i = 0; i < 3; ++i) {
    const StereoFrame f = renderFrame(scene, qvgaCamera(), floorAndSphereView(i));
    ASSERT_TRUE(writer->writeFrame(i, 0.1 * (i + 1), floorAndSphereView(i), f.disparity_px, f.color,
                                   cv::Mat(), &error))
        << error;
  }
  const std::string out_a = (seq / "out_a").string(), out_b = (seq / "out_b").string();
  const std::string map_path = (seq / "map.sfmap").string();
  FuseOptions a;
  ASSERT_TRUE(
      parseFuseArguments({seq.string(), out_a, "--quiet", "--save-map", map_path}, &a, &error))
      << error;
  FuseReport report;
  ASSERT_TRUE(runOfflineFusion(a, &report, &error)) << error;
  ASSERT_EQ(report.frames_used, 3u);
  ASSERT_TRUE(fs::exists(map_path));

  FuseOptions b;
  ASSERT_TRUE(parseFuseArguments({out_b, "--quiet", "--load-map", map_path}, &b, &error)) << error;
  ASSERT_TRUE(runOfflineFusion(b, &report, &error)) << error;
  EXPECT_EQ(report.frames_total, 0u);
  EXPECT_TRUE(readBytes(out_a + "/mesh.ply") == readBytes(out_b + "/mesh.ply"));
  std::ifstream stats_file(out_b + "/stats.json");
  const nlohmann::json stats = nlohmann::json::parse(stats_file);
  EXPECT_EQ(stats["map"]["loaded_blocks"], report.blocks);

  // A corrupted map is one clear error, and nothing is written.
  std::vector<uint8_t> bytes = readBytes(map_path);
  bytes.resize(bytes.size() - 1);
  writeBytes(map_path, bytes);
  FuseOptions c;
  ASSERT_TRUE(parseFuseArguments({(seq / "out_c").string(), "--quiet", "--load-map", map_path}, &c,
                                 &error));
  EXPECT_FALSE(runOfflineFusion(c, &report, &error));
  EXPECT_NE(error.find("truncated map file"), std::string::npos) << error;
  EXPECT_FALSE(fs::exists(seq / "out_c" / "mesh.ply"));
  // Without --load-map the input folder stays required.
  FuseOptions d;
  EXPECT_FALSE(parseFuseArguments({out_b, "--quiet"}, &d, &error));
  EXPECT_NE(error.find("or <out-dir> with --load-map"), std::string::npos) << error;
  fs::remove_all(seq);
}
