// The one place a surface vertex is formed, so that every path places and colours it alike.
#pragma once
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cstdint>

#include "MesherContext.h"

namespace stereo_fusion::mesher {

/// Appends the surface vertex on edge a → b (a before b lexicographically) to the submesh.
inline void appendVertex(MesherContext& ctx, const int a[3], const PointSample& sa, const int b[3],
                         const PointSample& sb) {
  // Eq. 2.11–2.12: k = (α − s1)/(s2 − s1) with α = 0. Kept off the end points so distinct
  // edges never produce coincident vertices.
  const float t = std::clamp(sa.sdf / (sa.sdf - sb.sdf), 1e-3f, 1.0f - 1e-3f);
  Eigen::Vector3d pos;
  for (int k = 0; k < 3; ++k) {
    const double ga = static_cast<double>(ctx.origin[k] + a[k]);
    const double gb = static_cast<double>(ctx.origin[k] + b[k]);
    pos[k] = (ga + t * (gb - ga)) * ctx.unit;
  }
  ctx.out->positions.push_back(pos.cast<float>());
  std::array<uint8_t, 3> rgb;
  for (int k = 0; k < 3; ++k)
    rgb[k] = static_cast<uint8_t>(
        std::clamp(sa.rgb[k] + t * (sb.rgb[k] - sa.rgb[k]) + 0.5f, 0.0f, 255.0f));
  ctx.out->colors.push_back(rgb);
}

}  // namespace stereo_fusion::mesher
