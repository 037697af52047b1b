// What one meshing thread reuses from owner to owner, so the hot path does not allocate.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "MesherVertexTable.h"
#include "stereo_fusion/map/Voxel.h"
#include "stereo_fusion/mesh/CellPolygonizer.h"

namespace stereo_fusion::mesher {

/// One lattice point's fused value.
struct PointSample {
  float sdf = 0.0f;
  float rgb[3] = {0, 0, 0};
};

/// Whether a grid point of the sample cache has been sampled, and with what outcome.
enum SampleState : uint8_t { kUnknown = 0, kObserved = 1, kUnobserved = 2 };

/// Per-thread buffers reused across mesh() calls (BlockMesher::mesh() keeps one per thread).
struct MeshScratch {
  std::vector<Voxel> seam_fills[8];   // face-filled copies of the neighbourhood's blocks
  std::vector<uint8_t> sample_state;  // SampleState per lattice grid point
  std::vector<PointSample> samples;   // per grid point, valid when kObserved
  // Generic-box scratch.
  std::vector<std::array<int, 3>> points;
  std::vector<PointSample> point_samples;  // per entry of `points`
  std::vector<std::vector<int>> polygons;  // only the first `polygon_count` are in use
  std::vector<int> grid_u, grid_v, lines, hanging;
  std::vector<float> values;
  std::vector<std::array<mc::Crossing, 3>> triangles;
  VertexTable vertex_of;  // edge → vertex, per owner
  // Uniform neighbourhoods: every box edge joins grid points one index apart on one axis, so
  // edge (grid point g, axis a) → slot 3g + a replaces hashing. A slot is live iff its stamp
  // is `uniform_edge_stamp` (bumped per owner, so no clearing).
  struct EdgeVertex {
    uint32_t stamp;
    uint32_t vertex;
  };
  std::vector<EdgeVertex> uniform_edge_vertex;
  uint32_t uniform_edge_stamp = 0;

  /// Readies uniform_edge_vertex for an owner whose sample grid has `points` points.
  void startUniformEdges(size_t points) {
    if (uniform_edge_vertex.size() < 3 * points)
      uniform_edge_vertex.resize(3 * points, EdgeVertex{0, 0});
    if (++uniform_edge_stamp == 0) {  // wrapped: stale stamps could match again
      for (EdgeVertex& slot : uniform_edge_vertex) slot.stamp = 0;
      uniform_edge_stamp = 1;
    }
  }
};

}  // namespace stereo_fusion::mesher
