// Fuzz target: calibration.yaml parsing. The bytes become calibration.yaml of a dataset folder
// whose poses.txt and one 4x3 disparity PFM are valid and fixed, so whatever DatasetReader
// decides depends on the calibration alone. An accepted calibration must give a usable camera,
// and loading the frame must either fail with a reason or match the calibrated size.
#include <opencv2/core.hpp>

#include "FuzzSupport.h"
#include "readers/DatasetReader.h"
#include "stereo_fusion/integration/StereoFrame.h"

using namespace stereo_fusion;

namespace {

const std::filesystem::path& folder() {
  static const std::filesystem::path dir = [] {
    const std::filesystem::path d = fuzz::scratchDir() / "seq";
    std::filesystem::create_directories(d / "disparity");
    fuzz::writeFile(d / "poses.txt", "0 0 0 0 0 0 0 1\n");
    std::string error;
    fuzz::require(writePfm((d / "disparity" / "000000.pfm").string(),
                           cv::Mat(3, 4, CV_32FC1, cv::Scalar(2.0f)), &error));
    return d;
  }();
  return dir;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::filesystem::path& dir = folder();
  fuzz::writeFile(dir / "calibration.yaml", std::string(reinterpret_cast<const char*>(data), size));
  std::string error;
  const auto reader = DatasetReader::open(dir.string(), &error);
  if (!reader) {
    fuzz::require(!error.empty());
    return 0;
  }
  const StereoCamera& camera = reader->camera();
  fuzz::require(camera.valid() && camera.width() > 0 && camera.height() > 0);
  fuzz::require(reader->size() == 1);
  StereoFrame frame;
  if (reader->load(0, &frame, &error)) {
    fuzz::require(frame.disparity_px.cols == camera.width() &&
                  frame.disparity_px.rows == camera.height());
    fuzz::require(validateFrame(frame, 0.16).empty());
  } else {
    fuzz::require(!error.empty());
  }
  return 0;
}
