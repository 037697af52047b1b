#include "stereo_fusion/mesh/TexturePatch.h"

#include <algorithm>
#include <cmath>

namespace stereo_fusion {

Eigen::Vector3f sampleBilinear(const cv::Mat& image, const Eigen::Vector2f& uv) {
  const float x = std::clamp(uv.x() * image.cols - 0.5f, 0.0f, static_cast<float>(image.cols - 1));
  const float y = std::clamp(uv.y() * image.rows - 0.5f, 0.0f, static_cast<float>(image.rows - 1));
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const int x1 = std::min(x0 + 1, image.cols - 1), y1 = std::min(y0 + 1, image.rows - 1);
  const float ax = x - x0, ay = y - y0;
  auto at = [&](int r, int c) {
    const cv::Vec3b& p = image.at<cv::Vec3b>(r, c);
    return Eigen::Vector3f(p[0], p[1], p[2]);
  };
  return (1 - ay) * ((1 - ax) * at(y0, x0) + ax * at(y0, x1)) +
         ay * ((1 - ax) * at(y1, x0) + ax * at(y1, x1));
}

}  // namespace stereo_fusion
