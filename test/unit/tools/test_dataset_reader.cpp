// Dataset folder reader and the offline fuser on folders written by the test itself.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "MeshTestSupport.h"
#include "fuser/FuseArguments.h"
#include "fuser/OfflineFuser.h"
#include "readers/DatasetReader.h"
#include "readers/ObjReader.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;
namespace fs = std::filesystem;

namespace {

std::string frameName(size_t i, const char* ext) {
  char name[32];
  std::snprintf(name, sizeof(name), "%06zu%s", i, ext);
  return name;
}

void writeText(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
}

/// A small sequence of a sphere on a floor: exact disparity as KITTI PNG, colour PNG,
/// optionally the right image too (rendered from the right camera).
struct SmallSequence {
  fs::path dir;
  std::vector<StereoFrame> frames;
  explicit SmallSequence(const std::string& name, int n = 3, bool with_right = false,
                         bool with_disparity = true) {
    dir = fs::path(testing::TempDir()) / ("stereo_fusion_" + name);
    fs::remove_all(dir);
    fs::create_directories(dir / "color");
    if (with_disparity) fs::create_directories(dir / "disparity");
    if (with_right) fs::create_directories(dir / "right");
    const StereoCamera cam = qvgaCamera();
    writeText(
        dir / "calibration.yaml",
        "width: 320\nheight: 240\nfx: 262.5\nfy: 262.5\ncx: 159.5\ncy: 119.5\nbaseline: 0.1\n");
    const sim::AnalyticScene scene = floorAndSphere();
    std::ofstream poses(dir / "poses.txt");
    poses.precision(17);
    poses << "# timestamp tx ty tz qx qy qz qw\n";
    for (int i = 0; i < n; ++i) {
      const Eigen::Isometry3d T =
          sim::lookAt({-0.1 + 0.1 * i, -0.2, 0.0}, {0.05, 0.1, 1.2}, -Eigen::Vector3d::UnitY());
      StereoFrame f = renderFrame(scene, cam, T);
      const Eigen::Quaterniond q(T.linear());
      poses << 0.1 * i << " " << T.translation().x() << " " << T.translation().y() << " "
            << T.translation().z() << " " << q.x() << " " << q.y() << " " << q.z() << " " << q.w()
            << "\n";
      cv::Mat bgr;
      cv::cvtColor(f.color, bgr, cv::COLOR_RGB2BGR);
      cv::imwrite((dir / "color" / frameName(i, ".png")).string(), bgr);
      if (with_disparity) {
        cv::Mat kitti;
        f.disparity_px.convertTo(kitti, CV_16UC1, 256.0);
        cv::imwrite((dir / "disparity" / frameName(i, ".png")).string(), kitti);
        f.disparity_px = kitti;  // keep the quantised values for comparison
        kitti.convertTo(f.disparity_px, CV_32FC1, 1.0 / 256.0);
      }
      if (with_right) {
        Eigen::Isometry3d T_right = T;
        T_right.translation() += T.linear() * Eigen::Vector3d(0.1, 0, 0);
        StereoFrame r = renderFrame(scene, cam, T_right);
        cv::Mat grey;
        cv::cvtColor(r.color, grey, cv::COLOR_RGB2GRAY);
        cv::imwrite((dir / "right" / frameName(i, ".png")).string(), grey);
      }
      frames.push_back(f);
    }
  }
  ~SmallSequence() { fs::remove_all(dir); }
};

std::string openError(const fs::path& dir) {
  std::string error;
  EXPECT_FALSE(DatasetReader::open(dir.string(), &error)) << "opened a bad folder";
  return error;
}

}  // namespace

TEST(DatasetReader, RoundTripOfWrittenFolder) {
  SmallSequence seq("roundtrip", 3);
  std::string error;
  auto reader = DatasetReader::open(seq.dir.string(), &error);
  ASSERT_TRUE(reader) << error;
  EXPECT_EQ(reader->size(), 3u);
  EXPECT_FALSE(reader->usesSgbm());
  EXPECT_EQ(reader->camera().width(), 320);
  EXPECT_DOUBLE_EQ(reader->camera().baseline(), 0.1);
  for (size_t i = 0; i < 3; ++i) {
    StereoFrame f;
    ASSERT_TRUE(reader->load(i, &f, &error)) << error;
    EXPECT_DOUBLE_EQ(f.timestamp_s, 0.1 * i);
    EXPECT_LT(
        (f.T_world_camera.matrix() - seq.frames[i].T_world_camera.matrix()).cwiseAbs().maxCoeff(),
        1e-9);
    EXPECT_EQ(cv::norm(f.disparity_px, seq.frames[i].disparity_px, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(f.color, seq.frames[i].color, cv::NORM_INF), 0.0);  // RGB order kept
  }
}

TEST(DatasetReader, PfmRoundTripAndTruncation) {
  const std::string path = testing::TempDir() + "stereo_fusion_test.pfm";
  cv::Mat image(7, 5, CV_32FC1);
  cv::randu(image, -3.0, 90.0);
  std::string error;
  ASSERT_TRUE(writePfm(path, image, &error)) << error;
  const cv::Mat back = readPfm(path, &error);
  ASSERT_FALSE(back.empty()) << error;
  EXPECT_EQ(cv::norm(image, back, cv::NORM_INF), 0.0);
  fs::resize_file(path, fs::file_size(path) - 10);
  EXPECT_TRUE(readPfm(path, &error).empty());
  EXPECT_NE(error.find("truncated"), std::string::npos) << error;
  writeText(path, "Pf\n100000 100000\n-1\nabcd");  // claims 40 GB: refused before allocating
  EXPECT_TRUE(readPfm(path, &error).empty());
  EXPECT_NE(error.find("truncated"), std::string::npos) << error;
  writeText(path, "P6\n5 7\n255\n");
  EXPECT_TRUE(readPfm(path, &error).empty());
  EXPECT_NE(error.find("not a PFM"), std::string::npos) << error;
  fs::remove(path);
}

TEST(DatasetReader, BadFoldersNameTheFileAndLine) {
  SmallSequence seq("bad", 2);
  const fs::path calib = seq.dir / "calibration.yaml";
  const fs::path poses = seq.dir / "poses.txt";
  std::string good_calib, good_poses;
  {
    std::ifstream a(calib), b(poses);
    good_calib.assign(std::istreambuf_iterator<char>(a), {});
    good_poses.assign(std::istreambuf_iterator<char>(b), {});
  }
  EXPECT_NE(openError(seq.dir / "nope").find("no such directory"), std::string::npos);

  fs::remove(calib);
  EXPECT_NE(openError(seq.dir).find("calibration.yaml: missing"), std::string::npos);
  writeText(calib, "width: 320\nheight: 240\nfx: 262.5\nfy: 262.5\ncx: 159.5\ncy: 119.5\n");
  EXPECT_NE(openError(seq.dir).find("missing key 'baseline'"), std::string::npos);
  writeText(calib,
            "width: 320\nheight: 240\nfx: 262.5\nfy: 262.5\ncx: 159.5\ncy: 119.5\nbaseline: 0\n");
  EXPECT_NE(openError(seq.dir).find("baseline"), std::string::npos);
  writeText(calib,
            "width: 320\nheight: 240\nfx: abc\nfy: 262.5\ncx: 159.5\ncy: 119.5\nbaseline: 0.1\n");
  EXPECT_NE(openError(seq.dir).find("calibration.yaml:3: 'fx' is not a number"), std::string::npos)
      << openError(seq.dir);
  writeText(
      calib,
      "width: -1e10\nheight: 240\nfx: 262.5\nfy: 262.5\ncx: 159.5\ncy: 119.5\nbaseline: 0.1\n");
  EXPECT_NE(openError(seq.dir).find("width and height must be whole pixel counts"),
            std::string::npos);
  writeText(calib, "width: [320\n");
  EXPECT_NE(openError(seq.dir).find("not valid YAML"), std::string::npos);
  writeText(calib, "%YAML:1.0\n" + good_calib);  // OpenCV FileStorage style is accepted
  std::string error;
  EXPECT_TRUE(DatasetReader::open(seq.dir.string(), &error)) << error;
  writeText(calib, good_calib);

  const std::string first_pose =
      good_poses.substr(0, good_poses.find('\n', good_poses.find('\n') + 1) + 1);
  writeText(poses, first_pose);  // comment + 1 pose for 2 frames
  EXPECT_NE(openError(seq.dir).find("1 poses for 2 frames"), std::string::npos)
      << openError(seq.dir);
  writeText(poses, good_poses + "0.3 1 2 x 0 0 0 1\n");
  EXPECT_NE(openError(seq.dir).find("poses.txt:4: expected 8 numbers"), std::string::npos)
      << openError(seq.dir);
  // An unusable pose on a well-formed line costs its frame only: the sequence opens, that frame
  // does not load and says why, the others load.
  for (const std::string& bad :
       {std::string("0.1 1 2 nan 0 0 0 1"), std::string("0.1 1 2 3 0 0 0 0"),
        std::string("0.1 1 2 3 0 0 0.5 1")}) {
    writeText(poses, "0 1 2 3 0 0 0 1\n" + bad + "\n");
    std::string open_error;
    const std::optional<DatasetReader> reader = DatasetReader::open(seq.dir.string(), &open_error);
    ASSERT_TRUE(reader) << bad << ": " << open_error;
    StereoFrame frame;
    std::string why;
    EXPECT_TRUE(reader->load(0, &frame, &why)) << why;
    EXPECT_FALSE(reader->load(1, &frame, &why)) << bad;
    EXPECT_NE(why.find("frame 1: " + (seq.dir / "poses.txt").string() + ":2: "), std::string::npos)
        << why;
    EXPECT_NE(why.find(bad.find("nan") != std::string::npos ? "pose is not finite"
                                                            : "quaternion is not unit length"),
              std::string::npos)
        << why;
  }
  writeText(poses, "0 1 2 3 0 0 0 1 9\n");
  EXPECT_NE(openError(seq.dir).find("poses.txt:1: expected 8 numbers"), std::string::npos);
  writeText(poses, good_poses);

  fs::remove(seq.dir / "color" / "000001.png");
  EXPECT_NE(openError(seq.dir).find("color/ has 1 images but there are 2 frames"),
            std::string::npos);
  fs::remove_all(seq.dir / "color");
  fs::remove_all(seq.dir / "disparity");
  EXPECT_NE(openError(seq.dir).find("no disparity/ images"), std::string::npos);
}

TEST(DatasetReader, BadSingleFramesFailToLoadWithTheFileName) {
  SmallSequence seq("badframes", 3);
  // Frame 1: truncated PNG. Frame 2: disparity of the wrong size.
  const fs::path truncated = seq.dir / "disparity" / "000001.png";
  fs::resize_file(truncated, fs::file_size(truncated) / 3);
  cv::imwrite((seq.dir / "disparity" / "000002.png").string(),
              cv::Mat(10, 10, CV_16UC1, cv::Scalar(500)));
  std::string error;
  auto reader = DatasetReader::open(seq.dir.string(), &error);
  ASSERT_TRUE(reader) << error;
  StereoFrame f;
  EXPECT_TRUE(reader->load(0, &f, &error)) << error;
  EXPECT_FALSE(reader->load(1, &f, &error));
  EXPECT_NE(error.find("000001.png"), std::string::npos) << error;
  EXPECT_FALSE(reader->load(2, &f, &error));
  EXPECT_NE(error.find("000002.png: disparity is 10x10 but calibration.yaml says 320x240"),
            std::string::npos)
      << error;
  EXPECT_FALSE(reader->load(7, &f, &error));
  // An 8-bit disparity PNG is not KITTI.
  cv::imwrite((seq.dir / "disparity" / "000002.png").string(),
              cv::Mat(240, 320, CV_8UC1, cv::Scalar(5)));
  EXPECT_FALSE(reader->load(2, &f, &error));
  EXPECT_NE(error.find("16-bit"), std::string::npos) << error;
}

TEST(DatasetReader, ComputesDisparityWithSgbmFromRightImages) {
  SmallSequence seq("sgbm", 1, /*with_right=*/true, /*with_disparity=*/false);
  std::string error;
  auto reader = DatasetReader::open(seq.dir.string(), &error);
  ASSERT_TRUE(reader) << error;
  EXPECT_TRUE(reader->usesSgbm());
  StereoFrame f;
  ASSERT_TRUE(reader->load(0, &f, &error)) << error;
  const cv::Mat& truth = seq.frames[0].disparity_px;
  std::vector<double> errors;
  int valid = 0, considered = 0;
  for (int v = 0; v < truth.rows; ++v)
    for (int u = 80; u < truth.cols; ++u) {  // SGBM has no result left of num_disparities
      if (truth.at<float>(v, u) <= 0) continue;
      ++considered;
      const float d = f.disparity_px.at<float>(v, u);
      if (d <= 0) continue;
      ++valid;
      errors.push_back(std::abs(d - truth.at<float>(v, u)));
    }
  std::printf("[ sgbm ] %d of %d pixels valid, median |error| %.3f px\n", valid, considered,
              median(errors));
  EXPECT_GT(valid, considered / 2);
  EXPECT_LT(median(errors), 0.5);
}

// Found by fuzz_dataset_folder: OpenCV's SGBM on an image no wider than its disparity range
// asked for a negative-sized buffer (or terminated from a destructor) instead of failing.
TEST(DatasetReader, SgbmRefusesImagesNoWiderThanItsDisparityRange) {
  SmallSequence seq("sgbm_narrow", 1, /*with_right=*/true, /*with_disparity=*/false);
  const int width = seq.frames[0].camera.width();
  SgbmParams sgbm;
  sgbm.num_disparities = (width + 15) / 16 * 16;  // >= width, a multiple of 16 as SGBM wants
  std::string error;
  EXPECT_FALSE(DatasetReader::open(seq.dir.string(), &error, sgbm));
  EXPECT_NE(
      error.find("calibration.yaml: images " + std::to_string(width) + " px wide are too narrow"),
      std::string::npos)
      << error;
  sgbm.num_disparities = (width - 1) / 16 * 16;  // the widest range that fits still works
  ASSERT_TRUE(DatasetReader::open(seq.dir.string(), &error, sgbm)) << error;
}

// Found by fuzz_dataset_folder: OpenCV's imread throws (instead of returning nothing) for a
// PFM header of width 0, and imread goes by content, so any image of the folder could do it.
TEST(DatasetReader, ImagesWhoseDecoderThrowsAreUnreadable) {
  for (const char* folder : {"color", "disparity"}) {
    SmallSequence seq(std::string("throwing_decoder_") + folder, 1);
    writeText(seq.dir / folder / "000000.png",
              std::string("Pf\n0 3\n-1\n") + std::string(48, '\0'));
    std::string error;
    auto reader = DatasetReader::open(seq.dir.string(), &error);
    ASSERT_TRUE(reader) << error;
    StereoFrame f;
    EXPECT_FALSE(reader->load(0, &f, &error));
    EXPECT_NE(error.find(std::string(folder) + "/000000.png: unreadable or truncated image"),
              std::string::npos)
        << error;
  }
}

TEST(OfflineFuser, WritesMeshAndStatsAndCountsSkippedFrames) {
  SmallSequence seq("fuse", 5);
  const fs::path truncated = seq.dir / "disparity" / "000002.png";
  fs::resize_file(truncated, fs::file_size(truncated) / 3);
  {  // frame 4's pose exported as NaN by a SLAM stack: that frame is skipped, not the run
    std::ifstream in(seq.dir / "poses.txt");
    std::string text, line;
    int pose_lines = 0;
    while (std::getline(in, line)) {
      if (!line.empty() && line[0] != '#' && pose_lines++ == 4)
        line = line.substr(0, line.find(' ')) + " nan 0 0 0 0 0 1";
      text += line + "\n";
    }
    in.close();
    std::ofstream(seq.dir / "poses.txt") << text;
  }
  FuseOptions options;
  std::string error;
  const fs::path out = fs::path(testing::TempDir()) / "stereo_fusion_fuse_out";
  fs::remove_all(out);
  ASSERT_TRUE(parseFuseArguments(
      {seq.dir.string(), out.string(), "--set", "voxel_size_m=0.03", "--quiet"}, &options, &error))
      << error;
  EXPECT_DOUBLE_EQ(options.config.voxel_size_m, 0.03);
  FuseReport report;
  ASSERT_TRUE(runOfflineFusion(options, &report, &error)) << error;
  EXPECT_EQ(report.frames_total, 5u);
  EXPECT_EQ(report.frames_used, 3u);
  EXPECT_EQ(report.skipped.at("unreadable"), 2u);
  EXPECT_GT(report.mesh_triangles, 500u);
  ASSERT_TRUE(fs::exists(out / "mesh.ply"));
  std::ifstream stats_file(out / "stats.json");
  const nlohmann::json stats = nlohmann::json::parse(stats_file);
  EXPECT_EQ(stats["frames"]["used"], 3);
  EXPECT_EQ(stats["frames"]["skipped_by_reason"]["unreadable"], 2);
  EXPECT_NE(stats["frames"]["skipped_examples"][0].get<std::string>().find("000002.png"),
            std::string::npos);
  EXPECT_NE(stats["frames"]["skipped_examples"][1].get<std::string>().find("frame 4: "),
            std::string::npos);
  EXPECT_NE(stats["frames"]["skipped_examples"][1].get<std::string>().find("poses.txt:"),
            std::string::npos);
  EXPECT_NE(stats["frames"]["skipped_examples"][1].get<std::string>().find("pose is not finite"),
            std::string::npos);
  EXPECT_EQ(stats["config"]["voxel_size_m"], "0.03");
  for (const char* stage : {"lookup", "fusion", "meshing", "total"})
    for (const char* stat : {"mean", "p50", "p99"})
      EXPECT_GE(stats["timings_ms"][stage][stat].get<double>(), 0.0);
  EXPECT_EQ(stats["blocks"]["total"].get<size_t>(), report.blocks);
  EXPECT_EQ(stats["blocks"]["meshed_at_8"].get<size_t>() +
                stats["blocks"]["meshed_at_4"].get<size_t>() +
                stats["blocks"]["meshed_at_2"].get<size_t>(),
            report.blocks);
  // The dense comparison grid covers at least the blocks' own voxels (512 finest voxels of 12 B
  // each per block), and a bounding box of them: at most its volume in blocks.
  const double dense_bytes = stats["memory"]["dense_grid_megabytes"].get<double>() * 1048576.0;
  EXPECT_GE(dense_bytes, report.blocks * 512.0 * 12.0 * (1 - 1e-9));
  EXPECT_NEAR(stats["memory"]["dense_grid_ratio"].get<double>(), dense_bytes / report.memory_bytes,
              1e-9);
  fs::remove_all(out);
}

// --mesh-every N: the mesh after the last frame is the same bytes as meshing every frame, and
// stats.json counts the meshing passes (frames 3 and 5 of 5: every 3rd, then the last).
TEST(OfflineFuser, MeshEveryNthFrameWritesTheSameMeshAndCountsMeshCalls) {
  SmallSequence seq("fuse_mesh_every", 5);
  auto run = [&](const std::string& name, const std::vector<std::string>& extra,
                 nlohmann::json* stats) {
    const fs::path out = fs::path(testing::TempDir()) / ("stereo_fusion_fuse_" + name);
    fs::remove_all(out);
    std::vector<std::string> args = {seq.dir.string(), out.string(), "--quiet"};
    args.insert(args.end(), extra.begin(), extra.end());
    FuseOptions options;
    std::string error;
    EXPECT_TRUE(parseFuseArguments(args, &options, &error)) << error;
    FuseReport report;
    EXPECT_TRUE(runOfflineFusion(options, &report, &error)) << error;
    std::ifstream stats_file(out / "stats.json");
    *stats = nlohmann::json::parse(stats_file);
    std::ifstream ply(out / "mesh.ply", std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(ply)), std::istreambuf_iterator<char>());
  };
  nlohmann::json every, third;
  const std::string mesh_every = run("every", {}, &every);
  const std::string mesh_third = run("third", {"--mesh-every", "3"}, &third);
  EXPECT_GT(mesh_every.size(), 10000u);
  EXPECT_TRUE(mesh_every == mesh_third);
  EXPECT_EQ(every["timings_ms"]["mesh_calls"], 5);
  EXPECT_EQ(third["timings_ms"]["mesh_calls"], 2);
  EXPECT_EQ(third["timings_ms"]["meshing"]["per"], "mesh call");
  EXPECT_EQ(third["timings_ms"]["lookup"]["per"], "frame");
  FuseOptions options;
  std::string error;
  EXPECT_FALSE(parseFuseArguments({"seq", "out", "--mesh-every", "0"}, &options, &error));
  EXPECT_NE(error.find("--mesh-every: '0' is not a number > 0"), std::string::npos) << error;
}

TEST(OfflineFuser, TexturePatchesAddObjMtlAndAtlasAndTheirMemoryToStats) {
  SmallSequence seq("fuse_textured", 3);
  FuseOptions options;
  std::string error;
  const fs::path out = fs::path(testing::TempDir()) / "stereo_fusion_fuse_textured_out";
  fs::remove_all(out);
  ASSERT_TRUE(parseFuseArguments(
      {seq.dir.string(), out.string(), "--set", "texture=patches", "--quiet"}, &options, &error))
      << error;
  FuseReport report;
  ASSERT_TRUE(runOfflineFusion(options, &report, &error)) << error;
  ASSERT_TRUE(fs::exists(out / "mesh.ply"));
  ASSERT_TRUE(fs::exists(out / "mesh.mtl"));
  ASSERT_TRUE(fs::exists(out / "mesh_atlas_0.png"));
  EXPECT_EQ(report.atlas_count, 1u);
  EXPECT_GT(report.textured_blocks, 5u);
  EXPECT_GT(report.texture_bytes, report.textured_blocks * 3 * 4);  // at least a few texels each
  EXPECT_LE(report.texture_bytes, report.textured_blocks * (3 * 64 * 64 + 8 * 2000 + 1024));
  ObjMesh obj;
  ASSERT_TRUE(readObj((out / "mesh.obj").string(), &obj, &error)) << error;
  EXPECT_EQ(obj.faces.size(), report.mesh_triangles);  // same triangles as the welded PLY
  std::ifstream stats_file(out / "stats.json");
  const nlohmann::json stats = nlohmann::json::parse(stats_file);
  EXPECT_EQ(stats["texture"]["textured_blocks"].get<size_t>(), report.textured_blocks);
  EXPECT_EQ(stats["texture"]["bytes"].get<size_t>(), report.texture_bytes);
  EXPECT_EQ(stats["config"]["texture"], "patches");
  fs::remove_all(out);
}

TEST(OfflineFuser, ArgumentErrorsNameTheProblem) {
  FuseOptions options;
  std::string error;
  EXPECT_FALSE(parseFuseArguments({"seq", "out", "--set", "voxel_size=0.01"}, &options, &error));
  EXPECT_NE(error.find("unknown parameter 'voxel_size'"), std::string::npos) << error;
  EXPECT_FALSE(parseFuseArguments({"seq", "out", "--set", "voxel_size_m=5"}, &options, &error));
  EXPECT_NE(error.find("out of range"), std::string::npos) << error;
  EXPECT_FALSE(parseFuseArguments({"seq", "out", "--set", "voxel_size_m"}, &options, &error));
  EXPECT_NE(error.find("key=value"), std::string::npos) << error;
  EXPECT_FALSE(parseFuseArguments({"seq", "out", "--bogus"}, &options, &error));
  EXPECT_NE(error.find("not expected: --bogus"), std::string::npos) << error;
  EXPECT_FALSE(parseFuseArguments({"seq"}, &options, &error));
  EXPECT_FALSE(parseFuseArguments({"seq", "out", "--frames", "-3"}, &options, &error));
  EXPECT_FALSE(
      parseFuseArguments({"seq", "out", "--config", "/nonexistent.yaml"}, &options, &error));
  EXPECT_NE(error.find("--config: File does not exist"), std::string::npos) << error;
  EXPECT_FALSE(parseFuseArguments({"seq", "out", "--set", "min_depth_m=9"}, &options, &error));
  EXPECT_NE(error.find("min_depth_m must be < max_depth_m"), std::string::npos) << error;
  FuseReport report;
  options = FuseOptions{};
  options.input = "/nonexistent-folder";
  options.out_dir = testing::TempDir() + "x";
  EXPECT_FALSE(runOfflineFusion(options, &report, &error));
  EXPECT_NE(error.find("/nonexistent-folder"), std::string::npos) << error;
}
