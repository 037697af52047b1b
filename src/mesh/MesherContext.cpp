#include "MesherContext.h"

#include <algorithm>
#include <iterator>

#include "MesherTables.h"

namespace stereo_fusion::mesher {

void MesherContext::buildSampleGrid() {
  for (int a = 0; a < 3; ++a) {
    uint64_t used = uint64_t{1} << kBlockUnits;  // bit q: coordinate q is in the grid
    for (int d = 0; d < 8; ++d)
      if (nb[d] != nullptr) used |= levelCentreBits(level[d]) << (((d >> a) & 1) * kBlockUnits);
    used &= (uint64_t{2} << kMaxBoxCoord) - 1;
    std::fill(std::begin(grid_index[a]), std::end(grid_index[a]), int8_t{-1});
    grid_dim[a] = 0;
    for (; used != 0; used &= used - 1) {
      const int q = __builtin_ctzll(used);
      grid_index[a][q] = static_cast<int8_t>(grid_dim[a]);
      grid_coords[a][grid_dim[a]++] = q;
    }
  }
  const size_t n = static_cast<size_t>(grid_dim[0]) * grid_dim[1] * grid_dim[2];
  scratch->sample_state.assign(n, kUnknown);
  if (scratch->samples.size() < n) scratch->samples.resize(n);
}

void MesherContext::buildLinePoints() {
  for (int axis = 0; axis < 3; ++axis)
    for (int ca = 0; ca < 3; ++ca)
      for (int cb = 0; cb < 3; ++cb)
        for (int du = 0; du < 2; ++du) {
          uint64_t bits = 0;
          for (int oa = ca == 2 ? 1 : 0; oa <= (ca >= 1 ? 1 : 0); ++oa)
            for (int ob = cb == 2 ? 1 : 0; ob <= (cb >= 1 ? 1 : 0); ++ob) {
              int off[3];
              off[axis] = du;
              off[(axis + 1) % 3] = oa;
              off[(axis + 2) % 3] = ob;
              const int d = off[0] + 2 * off[1] + 4 * off[2];
              if (nb[d] == nullptr) continue;
              bits |= levelCentreBits(level[d]) << (kBlockUnits * du);
            }
          line_points[axis][ca][cb][du] = bits;
        }
}

}  // namespace stereo_fusion::mesher
