#pragma once
#include <cstdint>

namespace stereo_fusion {

/// One SDF sample. The signed distance is stored in metres (negative in front of the
/// surface, positive behind it, thesis eq. 3.15); weight 0 means "never observed".
/// Colour uses the same running weight as the SDF (thesis eq. 3.8–3.9 applied to RGB).
struct Voxel {
  float sdf_m = 0.0f;
  float weight = 0.0f;
  uint8_t r = 0, g = 0, b = 0;
  uint8_t reserved = 0;  // keeps the voxel at 12 bytes and 4-byte aligned
};
static_assert(sizeof(Voxel) == 12,
              "Voxel must stay 12 bytes: the memory figures of doc/maps.md rely on it");

}  // namespace stereo_fusion
