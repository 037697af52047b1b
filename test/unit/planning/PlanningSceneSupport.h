#pragma once
// The Mapper the planning layer's scene tests fuse analytic scenes into.

#include "stereo_fusion/MapperConfig.h"

namespace stereo_fusion::test {

/// Defaults but for a 6 m depth range (the scenes' far walls) and no mesh (not under test).
inline MapperConfig planningSceneConfig() {
  MapperConfig c;
  c.max_depth_m = 6.0;
  c.mesh_enabled = false;
  return c;
}

}  // namespace stereo_fusion::test
