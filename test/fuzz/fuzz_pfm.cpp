// Fuzz target: the PFM reader (readPfm) on arbitrary file contents. A PFM it accepts must be a
// finite-sized single-channel float image with every pixel readable.
#include <opencv2/core.hpp>

#include "FuzzSupport.h"
#include "readers/DatasetReader.h"

using namespace stereo_fusion;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = (fuzz::scratchDir() / "input.pfm").string();
  fuzz::writeFile(path, std::string(reinterpret_cast<const char*>(data), size));
  std::string error;
  const cv::Mat image = readPfm(path, &error);
  if (image.empty()) {
    fuzz::require(!error.empty());  // a refusal always says why
    return 0;
  }
  fuzz::require(image.type() == CV_32FC1 && image.rows > 0 && image.cols > 0);
  // The image can only come from bytes that were in the file.
  fuzz::require(static_cast<size_t>(image.total()) * sizeof(float) <= size);
  // Touch every pixel so ASan sees any read past the decoded data.
  volatile float sink = 0.0f;
  for (int v = 0; v < image.rows; ++v)
    for (int u = 0; u < image.cols; ++u) sink = sink + image.at<float>(v, u);
  return 0;
}
