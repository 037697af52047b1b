#include "stereo_fusion/integration/DisparityCoherence.h"

#include <atomic>
#include <cmath>

namespace stereo_fusion {

DisparityCoherence measureDisparityCoherence(const cv::Mat& disparity_px,
                                             const MeasurementImage& measurements,
                                             ThreadPool* pool) {
  const int width = measurements.width(), height = measurements.height();
  const float* depth = measurements.depths();
  std::atomic<size_t> usable{0}, coherent{0};
  pool->parallelFor(static_cast<size_t>(height), 16, [&](size_t begin, size_t end) {
    size_t chunk_usable = 0, chunk_coherent = 0;
    for (size_t v = begin; v < end; ++v) {
      const int row = static_cast<int>(v);
      const float* d = disparity_px.ptr<float>(row);
      const float* z = depth + v * width;
      for (int u = 0; u < width; ++u) {
        if (std::isnan(z[u])) continue;
        ++chunk_usable;
        bool agrees = false;
        for (int dv = -1; dv <= 1 && !agrees; ++dv) {
          const int nv = row + dv;
          if (nv < 0 || nv >= height) continue;
          const float* nd = disparity_px.ptr<float>(nv);
          const float* nz = depth + static_cast<size_t>(nv) * width;
          for (int du = -1; du <= 1; ++du) {
            const int nu = u + du;
            if ((du == 0 && dv == 0) || nu < 0 || nu >= width || std::isnan(nz[nu])) continue;
            if (std::fabs(nd[nu] - d[u]) <= kCoherenceTolerancePx) {
              agrees = true;
              break;
            }
          }
        }
        chunk_coherent += agrees;
      }
    }
    usable += chunk_usable;
    coherent += chunk_coherent;
  });
  return {usable.load(), coherent.load()};
}

}  // namespace stereo_fusion
