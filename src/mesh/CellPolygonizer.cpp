#include "stereo_fusion/mesh/CellPolygonizer.h"

#include <cassert>
#include <stdexcept>

namespace stereo_fusion::mc {

namespace {
Crossing crossingOf(int p, int q) { return p < q ? Crossing{p, q} : Crossing{q, p}; }
}  // namespace

void polygonizeCell(const std::vector<std::vector<int>>& polygons, const float* values,
                    std::vector<std::array<Crossing, 3>>* triangles) {
  // Oriented segments start → end, one per run of inside corners of every polygon.
  struct Segment {
    Crossing start, end;
    bool used = false;
  };
  // Per-thread buffers: the mesher calls this for every irregular seam cell.
  thread_local std::vector<Segment> segments;
  thread_local std::vector<Crossing> crossings;  // per polygon, in walking order
  thread_local std::vector<bool> entering;
  thread_local std::vector<Crossing> loop;
  segments.clear();
  for (const std::vector<int>& poly : polygons) {
    const size_t n = poly.size();
    crossings.clear();
    entering.clear();
    for (size_t i = 0; i < n; ++i) {
      const int p = poly[i], q = poly[(i + 1) % n];
      const bool in_p = values[p] >= 0.0f, in_q = values[q] >= 0.0f;
      if (in_p == in_q) continue;
      crossings.push_back(crossingOf(p, q));
      entering.push_back(in_q);  // outside → inside: a run of inside corners starts here
    }
    if (crossings.empty()) continue;
    // Crossings alternate entering / leaving; pair each entering one with the next leaving.
    const size_t m = crossings.size();
    for (size_t i = 0; i < m; ++i) {
      if (!entering[i]) continue;
      segments.push_back({crossings[i], crossings[(i + 1) % m]});
    }
  }
  // Link segments into loops: each crossing starts exactly one segment and ends one.
  for (size_t s = 0; s < segments.size(); ++s) {
    if (segments[s].used) continue;
    loop.clear();
    size_t current = s;
    while (!segments[current].used) {
      segments[current].used = true;
      loop.push_back(segments[current].start);
      const Crossing next = segments[current].end;
      size_t found = segments.size();
      for (size_t t = 0; t < segments.size(); ++t)
        if (!segments[t].used && segments[t].start == next) {
          found = t;
          break;
        }
      if (found == segments.size()) break;  // loop closed (or malformed input)
      current = found;
    }
    for (size_t i = 1; i + 1 < loop.size(); ++i)
      triangles->push_back({loop[0], loop[i], loop[i + 1]});
  }
}

const std::array<CubeEdge, 12>& cubeEdges() {
  static const std::array<CubeEdge, 12> edges = {{{0, 1},
                                                  {2, 3},
                                                  {4, 5},
                                                  {6, 7},  // along x
                                                  {0, 2},
                                                  {1, 3},
                                                  {4, 6},
                                                  {5, 7},  // along y
                                                  {0, 4},
                                                  {1, 5},
                                                  {2, 6},
                                                  {3, 7}}};  // along z
  return edges;
}

const std::vector<std::vector<int>>& cubeFaces() {
  static const std::vector<std::vector<int>> faces = {{0, 4, 6, 2}, {1, 3, 7, 5},   // x = 0, x = 1
                                                      {0, 1, 5, 4}, {2, 6, 7, 3},   // y = 0, y = 1
                                                      {0, 2, 3, 1}, {4, 5, 7, 6}};  // z = 0, z = 1
  return faces;
}

const CaseTable& caseTable() {
  static const CaseTable table = [] {
    CaseTable t;
    int edge_of[8][8];
    for (auto& row : edge_of)
      for (int& e : row) e = -1;
    for (int e = 0; e < 12; ++e) {
      edge_of[cubeEdges()[e].corner_a][cubeEdges()[e].corner_b] = e;
      edge_of[cubeEdges()[e].corner_b][cubeEdges()[e].corner_a] = e;
    }
    std::vector<std::array<Crossing, 3>> triangles;
    for (int k = 0; k < 256; ++k) {
      float values[8];
      for (int c = 0; c < 8; ++c) values[c] = (k >> c) & 1 ? 1.0f : -1.0f;
      triangles.clear();
      polygonizeCell(cubeFaces(), values, &triangles);
      for (const auto& tri : triangles) {
        std::array<uint8_t, 3> edges{};
        for (int v = 0; v < 3; ++v) {
          const int e = edge_of[tri[v].a][tri[v].b];
          if (e < 0) throw std::logic_error("marching cubes table: crossing off a cube edge");
          edges[v] = static_cast<uint8_t>(e);
        }
        t.triangles[k].push_back(edges);
      }
    }
    return t;
  }();
  return table;
}

}  // namespace stereo_fusion::mc
