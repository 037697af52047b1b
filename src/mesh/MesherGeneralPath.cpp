#include "MesherGeneralPath.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <vector>

#include "MesherSampling.h"
#include "MesherSurfaceVertex.h"
#include "stereo_fusion/mesh/CellPolygonizer.h"

namespace stereo_fusion::mesher {
namespace {

void collectHangingPoints(const MesherContext& ctx, int axis, const int fixed[3], int u0, int u1,
                          std::vector<int>* points) {
  // Every lattice point, of any block touching this line, strictly inside (u0, u1), ascending.
  points->clear();
  for (uint64_t bits = ctx.hangingBits(axis, fixed, u0, u1); bits != 0; bits &= bits - 1)
    points->push_back(__builtin_ctzll(bits));
}

void faceInteriorLine(int normal_axis, int line_axis, const int lo[3], int fixed[3]) {
  // Lines across a face lying on a block face are both touching blocks' centre planes: the
  // lattice points of a line through the face's interior, where only those two blocks touch.
  const int other = 3 - normal_axis - line_axis;
  fixed[0] = lo[0];
  fixed[1] = lo[1];
  fixed[2] = lo[2];
  fixed[normal_axis] = kBlockUnits;
  fixed[other] = lo[other] >= kBlockUnits ? kBlockUnits + kBlockUnits / 2 : kBlockUnits / 2;
}

void faceGridLines(const MesherContext& ctx, int normal_axis, int line_axis, const int lo[3],
                   const int hi[3], std::vector<int>* lines) {
  int fixed[3];
  faceInteriorLine(normal_axis, line_axis, lo, fixed);
  collectHangingPoints(ctx, line_axis, fixed, lo[line_axis], hi[line_axis], lines);
}

uint32_t vertexOnEdge(MesherContext& ctx, const int p[3], const PointSample& sp, const int q[3],
                      const PointSample& sq) {
  // Canonical direction (lexicographic), so every owner computes identical bits.
  const bool swap = lexLess(q, p);
  const int* a = swap ? q : p;
  const int* b = swap ? p : q;
  const PointSample& sa = swap ? sq : sp;
  const PointSample& sb = swap ? sp : sq;
  const uint64_t key = (packPoint(a) << 18) | packPoint(b);
  bool inserted = false;
  const uint32_t vertex = ctx.scratch->vertex_of.findOrInsert(
      key, static_cast<uint32_t>(ctx.out->positions.size()), &inserted);
  if (inserted) appendVertex(ctx, a, sa, b, sb);
  return vertex;
}

bool boxHasNoSurface(MesherContext& ctx, const int lo[3], const int hi[3]) {
  // Every point a generic box uses (corners, hanging points, face grid crossings) is a grid
  // point inside the closed box: if all of those are observed and share one sign, the box
  // has no crossing. Conservative: an unobserved grid point means "cannot tell".
  bool negative = false, positive = false;
  for (int iz = ctx.grid_index[2][lo[2]]; iz <= ctx.grid_index[2][hi[2]]; ++iz)
    for (int iy = ctx.grid_index[1][lo[1]]; iy <= ctx.grid_index[1][hi[1]]; ++iy)
      for (int ix = ctx.grid_index[0][lo[0]]; ix <= ctx.grid_index[0][hi[0]]; ++ix) {
        const int q[3] = {ctx.grid_coords[0][ix], ctx.grid_coords[1][iy], ctx.grid_coords[2][iz]};
        PointSample sample;
        if (!cachedSample(ctx, q, &sample)) return false;
        (sample.sdf >= 0.0f ? positive : negative) = true;
        if (positive && negative) return false;
      }
  return true;
}

void meshPlainBox(MesherContext& ctx, const int corner[8][3], const PointSample s[8]) {
  int case_index = 0;
  for (int c = 0; c < 8; ++c) case_index |= (s[c].sdf >= 0.0f) << c;
  const auto& edges = mc::cubeEdges();
  for (const mc::CubeEdge& e : edges) {
    const float va = s[e.corner_a].sdf, vb = s[e.corner_b].sdf;
    if ((va >= 0.0f) != (vb >= 0.0f) && std::min(std::abs(va), std::abs(vb)) >= ctx.truncated_abs)
      return;  // truncation-band edge, not a surface
  }
  // Most crossing edges serve two triangles of the box: look each up once. (The first use of
  // an edge still comes first, so vertices are numbered as before.)
  constexpr uint32_t kNoVertex = ~uint32_t{0};
  uint32_t edge_vertex[12];
  std::fill(std::begin(edge_vertex), std::end(edge_vertex), kNoVertex);
  for (const auto& tri : mc::caseTable().triangles[case_index]) {
    std::array<uint32_t, 3> t;
    for (int v = 0; v < 3; ++v) {
      uint32_t& vertex = edge_vertex[tri[v]];
      if (vertex == kNoVertex) {
        const mc::CubeEdge& e = edges[tri[v]];
        vertex =
            vertexOnEdge(ctx, corner[e.corner_a], s[e.corner_a], corner[e.corner_b], s[e.corner_b]);
      }
      t[v] = vertex;
    }
    ctx.out->triangles.push_back(t);
  }
}

void meshGenericBox(MesherContext& ctx, const int lo[3], const int hi[3]) {
  // Generic box: tile each face, put every lattice point on an edge into the polygons.
  MeshScratch& m = *ctx.scratch;
  std::vector<std::array<int, 3>>& points = m.points;
  points.clear();
  auto pointId = [&](const int q[3]) {
    // Few points per box (corners + hanging points): a linear search beats hashing.
    for (size_t i = 0; i < points.size(); ++i)
      if (points[i][0] == q[0] && points[i][1] == q[1] && points[i][2] == q[2])
        return static_cast<int>(i);
    points.push_back({q[0], q[1], q[2]});
    return static_cast<int>(points.size() - 1);
  };
  size_t polygon_count = 0;
  for (auto& poly : m.polygons) poly.clear();  // unused trailing polygons stay empty
  std::vector<int>& grid_u = m.grid_u;
  std::vector<int>& grid_v = m.grid_v;
  std::vector<int>& hanging = m.hanging;
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (int side = 0; side < 2; ++side) {
      const int plane = side ? hi[axis] : lo[axis];
      grid_u.assign(1, lo[u]);
      grid_v.assign(1, lo[v]);
      if (plane == kBlockUnits) {
        faceGridLines(ctx, axis, u, lo, hi, &m.lines);
        grid_u.insert(grid_u.end(), m.lines.begin(), m.lines.end());
        faceGridLines(ctx, axis, v, lo, hi, &m.lines);
        grid_v.insert(grid_v.end(), m.lines.begin(), m.lines.end());
      }
      grid_u.push_back(hi[u]);
      grid_v.push_back(hi[v]);
      for (size_t iu = 0; iu + 1 < grid_u.size(); ++iu)
        for (size_t iv = 0; iv + 1 < grid_v.size(); ++iv) {
          // Tile corners counter-clockwise seen from outside (e_u × e_v = e_axis).
          int cu[4] = {grid_u[iu], grid_u[iu + 1], grid_u[iu + 1], grid_u[iu]};
          int cv[4] = {grid_v[iv], grid_v[iv], grid_v[iv + 1], grid_v[iv + 1]};
          if (side == 0) {
            std::swap(cu[1], cu[3]);
            std::swap(cv[1], cv[3]);
          }
          if (polygon_count == m.polygons.size()) m.polygons.emplace_back();
          std::vector<int>& poly = m.polygons[polygon_count++];
          for (int c = 0; c < 4; ++c) {
            int p[3];
            p[axis] = plane;
            p[u] = cu[c];
            p[v] = cv[c];
            poly.push_back(pointId(p));
            // Points on the tile edge towards the next corner, in walking order.
            const int n = (c + 1) % 4;
            const int edge_axis = cu[c] != cu[n] ? u : v;
            const int from = edge_axis == u ? cu[c] : cv[c];
            const int to = edge_axis == u ? cu[n] : cv[n];
            collectHangingPoints(ctx, edge_axis, p, std::min(from, to), std::max(from, to),
                                 &hanging);
            if (from > to) std::reverse(hanging.begin(), hanging.end());
            for (int h : hanging) {
              int hp[3] = {p[0], p[1], p[2]};
              hp[edge_axis] = h;
              poly.push_back(pointId(hp));
            }
          }
        }
    }
  }
  std::vector<PointSample>& samples = m.point_samples;
  samples.resize(points.size());
  m.values.resize(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    if (!cachedSample(ctx, points[i].data(), &samples[i])) return;
    m.values[i] = samples[i].sdf;
  }
  const float* values = m.values.data();
  m.triangles.clear();
  mc::polygonizeCell(m.polygons, values, &m.triangles);  // empty trailing polygons add nothing
  for (const auto& tri : m.triangles)
    for (const mc::Crossing& c : tri)
      if (std::min(std::abs(values[c.a]), std::abs(values[c.b])) >= ctx.truncated_abs) return;
  for (const auto& tri : m.triangles) {
    std::array<uint32_t, 3> t;
    for (int k = 0; k < 3; ++k)
      t[k] = vertexOnEdge(ctx, points[tri[k].a].data(), samples[tri[k].a], points[tri[k].b].data(),
                          samples[tri[k].b]);
    ctx.out->triangles.push_back(t);
  }
}

}  // namespace

bool boxIsPlain(const MesherContext& ctx, const int lo[3], const int hi[3]) {
  // Plain boxes (8 corners, nothing on their edges or faces) use the case table. Only a box
  // touching a block face can carry extra points, and only when levels differ.
  if (ctx.uniform || !(hi[0] == kBlockUnits || hi[1] == kBlockUnits || hi[2] == kBlockUnits ||
                       lo[0] == kBlockUnits || lo[1] == kBlockUnits || lo[2] == kBlockUnits))
    return true;
  for (int axis = 0; axis < 3; ++axis)
    for (int c = 0; c < 4; ++c) {
      const int a = (axis + 1) % 3, b = (axis + 2) % 3;
      int fixed[3];
      fixed[a] = (c & 1) ? hi[a] : lo[a];
      fixed[b] = (c & 2) ? hi[b] : lo[b];
      fixed[axis] = lo[axis];
      if (ctx.hangingBits(axis, fixed, lo[axis], hi[axis]) != 0) return false;
    }
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      if ((side ? hi[axis] : lo[axis]) != kBlockUnits) continue;
      for (int k = 1; k < 3; ++k) {
        const int line_axis = (axis + k) % 3;
        int fixed[3];
        faceInteriorLine(axis, line_axis, lo, fixed);
        if (ctx.hangingBits(line_axis, fixed, lo[line_axis], hi[line_axis]) != 0) return false;
      }
    }
  return true;
}

void meshBox(MesherContext& ctx, const int lo[3], const int hi[3]) {
  // The 8 corners first: both the plain and the generic path give up on a box with an
  // unobserved corner, and most boxes have no sign change at all.
  int corner[8][3];
  PointSample s[8];
  int case_index = 0;
  for (int c = 0; c < 8; ++c) {
    corner[c][0] = (c & 1) ? hi[0] : lo[0];
    corner[c][1] = (c & 2) ? hi[1] : lo[1];
    corner[c][2] = (c & 4) ? hi[2] : lo[2];
    if (!cachedSample(ctx, corner[c], &s[c])) return;
    case_index |= (s[c].sdf >= 0.0f) << c;
  }
  const bool single_sign = case_index == 0 || case_index == 255;
  if (boxIsPlain(ctx, lo, hi)) {
    if (!single_sign) meshPlainBox(ctx, corner, s);
    return;
  }
  // Hanging points may change sign even when the corners do not.
  if (single_sign && boxHasNoSurface(ctx, lo, hi)) return;
  meshGenericBox(ctx, lo, hi);
}

void meshEveryBox(MesherContext& ctx) {
  ctx.buildLinePoints();
  BoxIntervals intervals;
  for (int d = 0; d < 8; ++d) {
    if (ctx.nb[d] == nullptr) continue;
    intervals.build(d, ctx.step[d]);
    for (int iz = 0; iz < intervals.count[2]; ++iz)
      for (int iy = 0; iy < intervals.count[1]; ++iy)
        for (int ix = 0; ix < intervals.count[0]; ++ix) {
          const int lo[3] = {intervals.bounds[0][ix].first, intervals.bounds[1][iy].first,
                             intervals.bounds[2][iz].first};
          const int hi[3] = {intervals.bounds[0][ix].second, intervals.bounds[1][iy].second,
                             intervals.bounds[2][iz].second};
          const bool core =
              d == 0 && hi[0] < kBlockUnits && hi[1] < kBlockUnits && hi[2] < kBlockUnits;
          // Most boxes: no voxel-level sign change, decided exactly on the corner voxels.
          if (core && ctx.coreBoxIsEmpty(lo)) continue;
          meshBox(ctx, lo, hi);
        }
  }
}

}  // namespace stereo_fusion::mesher
