// Fuzz target: a whole dataset folder through DatasetReader::open() and load().
// Input layout: one flag byte, then sections separated by kSeparator:
//   calibration.yaml | poses.txt | image A | image B
// flags bit 0: image A is disparity/000000.pfm (else disparity/000000.png)
//       bit 1: image B is color/000000.png
//       bit 2: image A is right/000000.png instead, so disparity comes from SGBM
// Whatever the bytes, open()/load() must return false with a reason or give a frame that keeps
// the reader's promises (CV_32FC1 disparity of the calibrated size, finite and >= 0).
#include <opencv2/core.hpp>

#include "FuzzSupport.h"
#include "readers/DatasetReader.h"
#include "stereo_fusion/integration/StereoFrame.h"
#include "stereo_fusion/map/BlockOctree.h"

using namespace stereo_fusion;
namespace fs = std::filesystem;

namespace {
const std::string kSeparator = "\n--8<--\n";
constexpr double kBlockSizeM = 0.16;

void checkFrame(const DatasetReader& reader, const StereoFrame& frame) {
  const StereoCamera& camera = reader.camera();
  const cv::Mat& d = frame.disparity_px;
  fuzz::require(d.type() == CV_32FC1 && d.cols == camera.width() && d.rows == camera.height());
  for (int v = 0; v < d.rows; ++v)
    for (int u = 0; u < d.cols; ++u)
      fuzz::require(std::isfinite(d.at<float>(v, u)) && d.at<float>(v, u) >= 0.0f);
  if (!frame.color.empty()) {
    fuzz::require(frame.color.type() == CV_8UC3 || frame.color.type() == CV_8UC1);
    fuzz::require(frame.color.size() == d.size());
  }
  // Images and camera are right by construction; only a pose beyond the map's range may be refused.
  const double range_m = kBlockSizeM * (BlockOctree::kMaxKey / 2);
  if (frame.T_world_camera.translation().cwiseAbs().maxCoeff() <= range_m)
    fuzz::require(validateFrame(frame, kBlockSizeM).empty());
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::ByteReader in(data, size);
  const uint8_t flags = in.u8();
  const std::string calibration = in.section(kSeparator);
  const std::string poses = in.section(kSeparator);
  const std::string image_a = in.section(kSeparator);
  const std::string image_b = in.section(kSeparator);

  const fs::path dir = fuzz::scratchDir() / "seq";
  fs::remove_all(dir);
  fs::create_directories(dir);
  fuzz::writeFile(dir / "calibration.yaml", calibration);
  fuzz::writeFile(dir / "poses.txt", poses);
  if (flags & 4) {
    fs::create_directories(dir / "right");
    fuzz::writeFile(dir / "right" / "000000.png", image_a);
  } else {
    fs::create_directories(dir / "disparity");
    fuzz::writeFile(dir / "disparity" / ((flags & 1) ? "000000.pfm" : "000000.png"), image_a);
  }
  if (flags & 2) {
    fs::create_directories(dir / "color");
    fuzz::writeFile(dir / "color" / "000000.png", image_b);
  }

  std::string error;
  const auto reader = DatasetReader::open(dir.string(), &error);
  if (!reader) {
    fuzz::require(!error.empty());
    return 0;
  }
  fuzz::require(reader->size() == 1);
  StereoFrame frame;
  if (reader->load(0, &frame, &error))
    checkFrame(*reader, frame);
  else
    fuzz::require(!error.empty());
  return 0;
}
