#include "stereo_fusion/mesh/BlockMesher.h"

#include <algorithm>
#include <Eigen/Geometry>
#include <cmath>

#include "stereo_fusion/mesh/CellPolygonizer.h"

namespace stereo_fusion {

namespace {
constexpr int kBlockUnits = 16;  // a block is 16 half-finest-voxel units wide

/// Offsets (0 or 1, relative to the owner) of the blocks touching coordinate q on one axis.
inline void incidentRange(int q, int* first, int* last) {
  *first = q > kBlockUnits ? 1 : 0;
  *last = q >= kBlockUnits ? 1 : 0;
}

inline uint64_t packPoint(const int q[3]) {
  return (static_cast<uint64_t>(q[0]) << 12) | (static_cast<uint64_t>(q[1]) << 6) |
         static_cast<uint64_t>(q[2]);
}

inline bool lexLess(const int a[3], const int b[3]) {
  if (a[0] != b[0]) return a[0] < b[0];
  if (a[1] != b[1]) return a[1] < b[1];
  return a[2] < b[2];
}

/// Trilinear interpolation of `block`'s samples at `level`, at block-local lattice
/// coordinates (0..16), clamped to the block's voxel centres. False if a sample that
/// contributes is unobserved.
bool blockField(const VoxelBlock& block, int level, const int local[3], float* sdf, float rgb[3]) {
  const int step = 1 << level;
  const int side = kFinestSide >> level;
  // Most points are voxel centres: read the voxel (what the interpolation below yields).
  const int den = 2 * step;
  if ((local[0] - step) % den == 0 && (local[1] - step) % den == 0 && (local[2] - step) % den == 0 &&
      local[0] > 0 && local[1] > 0 && local[2] > 0 && local[0] < kBlockUnits &&
      local[1] < kBlockUnits && local[2] < kBlockUnits) {
    const Voxel& v = block.at(level, (local[0] - step) / den, (local[1] - step) / den, (local[2] - step) / den);
    if (!(v.weight > 0.0f)) return false;
    *sdf = v.sdf_m;
    rgb[0] = v.r;
    rgb[1] = v.g;
    rgb[2] = v.b;
    return true;
  }
  int i0[3];
  float frac[3];
  for (int a = 0; a < 3; ++a) {
    const int num = std::clamp(local[a] - step, 0, (side - 1) * den);
    i0[a] = num / den;
    int rem = num % den;
    if (i0[a] == side - 1) {  // on the last centre: use the last cell with fraction 1
      i0[a] = side - 2;
      rem = den;
    }
    frac[a] = static_cast<float>(rem) / static_cast<float>(den);
  }
  float acc = 0.0f, acc_rgb[3] = {0, 0, 0};
  for (int c = 0; c < 8; ++c) {
    const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
    const float w = (dx ? frac[0] : 1.0f - frac[0]) * (dy ? frac[1] : 1.0f - frac[1]) *
                    (dz ? frac[2] : 1.0f - frac[2]);
    if (w == 0.0f) continue;
    const Voxel& v = block.at(level, i0[0] + dx, i0[1] + dy, i0[2] + dz);
    if (!(v.weight > 0.0f)) return false;
    acc += w * v.sdf_m;
    acc_rgb[0] += w * v.r;
    acc_rgb[1] += w * v.g;
    acc_rgb[2] += w * v.b;
  }
  *sdf = acc;
  for (int k = 0; k < 3; ++k) rgb[k] = acc_rgb[k];
  return true;
}
}  // namespace

int chooseMeshLevel(const VoxelBlock& block, double level_min_coverage) {
  // Observed surface area of each level, in finest-voxel units: a level's band is
  // truncation_vox of its own voxels thick, so area ≈ observed volume / thickness ∝ n · s².
  // Areas, not voxel shares: a coarse centre can miss the band that finer centres near the
  // block's faces catch, so no level is assumed to contain another.
  double area[kNumLevels];
  double largest = 0.0;
  for (int level = 0; level < kNumLevels; ++level) {
    int observed = 0;
    for (int n = 0; n < levelVoxelCount(level); ++n)
      observed += block.voxels[levelOffset(level) + n].weight > 0.0f;
    const double scale = levelScale(level);
    area[level] = observed * scale * scale;
    largest = std::max(largest, area[level]);
  }
  for (int level = 0; level < kNumLevels; ++level)
    if (largest > 0.0 && area[level] >= level_min_coverage * largest) return level;
  return kNumLevels - 1;
}

void refreshMeshLevel(VoxelBlock* block, double level_min_coverage) {
  const int level = chooseMeshLevel(*block, level_min_coverage);
  block->mesh_level = static_cast<int8_t>(level);
  block->mesh_has_negative = block->mesh_has_positive = false;
  for (int n = 0; n < levelVoxelCount(level); ++n) {
    const Voxel& v = block->voxels[levelOffset(level) + n];
    if (!(v.weight > 0.0f)) continue;
    (v.sdf_m < 0.0f ? block->mesh_has_negative : block->mesh_has_positive) = true;
  }
}

struct BlockMesher::Context {
  const VoxelBlock* nb[8] = {};  // owner + (d & 1, (d >> 1) & 1, (d >> 2) & 1)
  int level[8] = {};
  int step[8] = {};
  bool uniform = true;  // every present neighbour has the owner's level
  float truncated_abs = 0.0f;  // 0.99 · Φ of the coarsest level present
  int64_t origin[3] = {};
  double unit = 0.0;
  SubMesh* out = nullptr;
  std::unordered_map<uint64_t, uint32_t> vertex_of;
  std::vector<PointSample> vertex_samples;  // scratch for the generic path
};

BlockMesher::BlockMesher(const MeshingParams& params) : params_(params) {}

bool BlockMesher::samplePoint(const Context& ctx, int qx, int qy, int qz, PointSample* out) const {
  const int q[3] = {qx, qy, qz};
  int first[3], last[3];
  for (int a = 0; a < 3; ++a) incidentRange(q[a], &first[a], &last[a]);
  float weight_sum = 0.0f, acc = 0.0f, acc_rgb[3] = {0, 0, 0};
  // Fixed order (z, y, x outer to inner): every owner sums a shared point identically.
  for (int dz = first[2]; dz <= last[2]; ++dz)
    for (int dy = first[1]; dy <= last[1]; ++dy)
      for (int dx = first[0]; dx <= last[0]; ++dx) {
        const int d = dx + 2 * dy + 4 * dz;
        const VoxelBlock* block = ctx.nb[d];
        if (block == nullptr) return false;
        const int local[3] = {qx - kBlockUnits * dx, qy - kBlockUnits * dy, qz - kBlockUnits * dz};
        float sdf, rgb[3];
        if (!blockField(*block, ctx.level[d], local, &sdf, rgb)) return false;
        const float w = 1.0f / static_cast<float>(ctx.step[d]);  // finer block, nearer centre
        weight_sum += w;
        acc += w * sdf;
        for (int k = 0; k < 3; ++k) acc_rgb[k] += w * rgb[k];
      }
  out->sdf = acc / weight_sum;
  for (int k = 0; k < 3; ++k) out->rgb[k] = acc_rgb[k] / weight_sum;
  return true;
}

void BlockMesher::collectHangingPoints(const Context& ctx, int axis, const int fixed[3], int u0,
                                       int u1, std::vector<int>* points) const {
  // Every lattice point, of any block touching this line, strictly inside (u0, u1).
  points->clear();
  forEachLatticePoint(ctx, axis, fixed, u0, u1, [&](int u) {
    points->push_back(u);
    return true;
  });
  std::sort(points->begin(), points->end());
  points->erase(std::unique(points->begin(), points->end()), points->end());
}

bool BlockMesher::hasHangingPoints(const Context& ctx, int axis, const int fixed[3], int u0,
                                   int u1) const {
  bool found = false;
  forEachLatticePoint(ctx, axis, fixed, u0, u1, [&](int) {
    found = true;
    return false;  // stop at the first
  });
  return found;
}

template <typename F>
void BlockMesher::forEachLatticePoint(const Context& ctx, int axis, const int fixed[3], int u0, int u1,
                                      F&& f) const {
  const int du = u0 >= kBlockUnits ? 1 : 0;
  const int a = (axis + 1) % 3, b = (axis + 2) % 3;
  int fa, la, fb, lb;
  incidentRange(fixed[a], &fa, &la);
  incidentRange(fixed[b], &fb, &lb);
  for (int oa = fa; oa <= la; ++oa)
    for (int ob = fb; ob <= lb; ++ob) {
      int off[3];
      off[axis] = du;
      off[a] = oa;
      off[b] = ob;
      const int d = off[0] + 2 * off[1] + 4 * off[2];
      if (ctx.nb[d] == nullptr) continue;
      const int step = ctx.step[d];
      for (int c = step; c < kBlockUnits; c += 2 * step) {
        const int u = kBlockUnits * du + c;
        if (u > u0 && u < u1 && !f(u)) return;
      }
    }
}

void BlockMesher::faceGridLines(const Context& ctx, int normal_axis, int line_axis, const int lo[3],
                                const int hi[3], std::vector<int>* lines) const {
  int fixed[3];
  faceInteriorLine(normal_axis, line_axis, lo, fixed);
  collectHangingPoints(ctx, line_axis, fixed, lo[line_axis], hi[line_axis], lines);
}

void BlockMesher::faceInteriorLine(int normal_axis, int line_axis, const int lo[3], int fixed[3]) {
  // Lines across a face lying on a block face are both touching blocks' centre planes: the
  // lattice points of a line through the face's interior, where only those two blocks touch.
  const int other = 3 - normal_axis - line_axis;
  fixed[0] = lo[0];
  fixed[1] = lo[1];
  fixed[2] = lo[2];
  fixed[normal_axis] = kBlockUnits;
  fixed[other] = lo[other] >= kBlockUnits ? kBlockUnits + kBlockUnits / 2 : kBlockUnits / 2;
}

uint32_t BlockMesher::vertexOnEdge(Context& ctx, const int p[3], const PointSample& sp,
                                   const int q[3], const PointSample& sq) const {
  // Canonical direction (lexicographic), so every owner computes identical bits.
  const bool swap = lexLess(q, p);
  const int* a = swap ? q : p;
  const int* b = swap ? p : q;
  const PointSample& sa = swap ? sq : sp;
  const PointSample& sb = swap ? sp : sq;
  const uint64_t key = (packPoint(a) << 18) | packPoint(b);
  auto [it, inserted] = ctx.vertex_of.try_emplace(key, static_cast<uint32_t>(ctx.out->positions.size()));
  if (!inserted) return it->second;
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
    rgb[k] = static_cast<uint8_t>(std::clamp(sa.rgb[k] + t * (sb.rgb[k] - sa.rgb[k]) + 0.5f, 0.0f, 255.0f));
  ctx.out->colors.push_back(rgb);
  return it->second;
}

void BlockMesher::meshBox(Context& ctx, const int lo[3], const int hi[3]) const {
  // Plain boxes (8 corners, nothing on their edges or faces) use the case table. Only a box
  // touching a block face can carry extra points, and only when levels differ.
  bool plain = true;
  if (!ctx.uniform && (hi[0] == kBlockUnits || hi[1] == kBlockUnits || hi[2] == kBlockUnits ||
                       lo[0] == kBlockUnits || lo[1] == kBlockUnits || lo[2] == kBlockUnits)) {
    for (int axis = 0; axis < 3 && plain; ++axis)
      for (int c = 0; c < 4 && plain; ++c) {
        const int a = (axis + 1) % 3, b = (axis + 2) % 3;
        int fixed[3];
        fixed[a] = (c & 1) ? hi[a] : lo[a];
        fixed[b] = (c & 2) ? hi[b] : lo[b];
        fixed[axis] = lo[axis];
        plain = !hasHangingPoints(ctx, axis, fixed, lo[axis], hi[axis]);
      }
    for (int axis = 0; axis < 3 && plain; ++axis)
      for (int side = 0; side < 2 && plain; ++side) {
        if ((side ? hi[axis] : lo[axis]) != kBlockUnits) continue;
        for (int k = 1; k < 3 && plain; ++k) {
          const int line_axis = (axis + k) % 3;
          int fixed[3];
          faceInteriorLine(axis, line_axis, lo, fixed);
          plain = !hasHangingPoints(ctx, line_axis, fixed, lo[line_axis], hi[line_axis]);
        }
      }
  }

  if (plain) {
    int corner[8][3];
    PointSample s[8];
    int case_index = 0;
    for (int c = 0; c < 8; ++c) {
      corner[c][0] = (c & 1) ? hi[0] : lo[0];
      corner[c][1] = (c & 2) ? hi[1] : lo[1];
      corner[c][2] = (c & 4) ? hi[2] : lo[2];
      if (!samplePoint(ctx, corner[c][0], corner[c][1], corner[c][2], &s[c])) return;
      case_index |= (s[c].sdf >= 0.0f) << c;
    }
    if (case_index == 0 || case_index == 255) return;
    const auto& edges = mc::cubeEdges();
    for (const mc::CubeEdge& e : edges) {
      const float va = s[e.corner_a].sdf, vb = s[e.corner_b].sdf;
      if ((va >= 0.0f) != (vb >= 0.0f) && std::min(std::abs(va), std::abs(vb)) >= ctx.truncated_abs)
        return;  // truncation-band edge, not a surface
    }
    for (const auto& tri : mc::caseTable().triangles[case_index]) {
      std::array<uint32_t, 3> t;
      for (int v = 0; v < 3; ++v) {
        const mc::CubeEdge& e = edges[tri[v]];
        t[v] = vertexOnEdge(ctx, corner[e.corner_a], s[e.corner_a], corner[e.corner_b], s[e.corner_b]);
      }
      ctx.out->triangles.push_back(t);
    }
    return;
  }

  // Generic box: tile each face, put every lattice point on an edge into the polygons.
  std::vector<std::array<int, 3>> points;
  std::unordered_map<uint64_t, int> id_of;
  auto pointId = [&](const int q[3]) {
    auto [it, inserted] = id_of.try_emplace(packPoint(q), static_cast<int>(points.size()));
    if (inserted) points.push_back({q[0], q[1], q[2]});
    return it->second;
  };
  std::vector<std::vector<int>> polygons;
  std::vector<int> lines_u, lines_v, hanging;
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (int side = 0; side < 2; ++side) {
      const int plane = side ? hi[axis] : lo[axis];
      std::vector<int> grid_u = {lo[u]}, grid_v = {lo[v]};
      if (plane == kBlockUnits) {
        faceGridLines(ctx, axis, u, lo, hi, &lines_u);
        faceGridLines(ctx, axis, v, lo, hi, &lines_v);
        grid_u.insert(grid_u.end(), lines_u.begin(), lines_u.end());
        grid_v.insert(grid_v.end(), lines_v.begin(), lines_v.end());
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
          std::vector<int> poly;
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
            collectHangingPoints(ctx, edge_axis, p, std::min(from, to), std::max(from, to), &hanging);
            if (from > to) std::reverse(hanging.begin(), hanging.end());
            for (int h : hanging) {
              int hp[3] = {p[0], p[1], p[2]};
              hp[edge_axis] = h;
              poly.push_back(pointId(hp));
            }
          }
          polygons.push_back(std::move(poly));
        }
    }
  }
  std::vector<PointSample>& samples = ctx.vertex_samples;
  samples.resize(points.size());
  std::vector<float> values(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    if (!samplePoint(ctx, points[i][0], points[i][1], points[i][2], &samples[i])) return;
    values[i] = samples[i].sdf;
  }
  std::vector<std::array<mc::Crossing, 3>> triangles;
  mc::polygonizeCell(polygons, values.data(), &triangles);
  for (const auto& tri : triangles)
    for (const mc::Crossing& c : tri)
      if (std::min(std::abs(values[c.a]), std::abs(values[c.b])) >= ctx.truncated_abs) return;
  for (const auto& tri : triangles) {
    std::array<uint32_t, 3> t;
    for (int k = 0; k < 3; ++k)
      t[k] = vertexOnEdge(ctx, points[tri[k].a].data(), samples[tri[k].a], points[tri[k].b].data(),
                          samples[tri[k].b]);
    ctx.out->triangles.push_back(t);
  }
}

void BlockMesher::mesh(const BlockOctree& map, const VoxelBlock& owner, SubMesh* out) const {
  out->clear();
  out->key = owner.key;
  out->level = owner.mesh_level;
  Context ctx;
  ctx.out = out;
  ctx.unit = params_.voxel_size_m / 2.0;
  ctx.origin[0] = int64_t{owner.key.x} * kBlockUnits;
  ctx.origin[1] = int64_t{owner.key.y} * kBlockUnits;
  ctx.origin[2] = int64_t{owner.key.z} * kBlockUnits;
  bool any_negative = false, any_positive = false;
  for (int d = 0; d < 8; ++d) {
    ctx.nb[d] = d == 0 ? &owner : map.find(owner.key.offset(d & 1, (d >> 1) & 1, (d >> 2) & 1));
    ctx.level[d] = ctx.nb[d] ? ctx.nb[d]->mesh_level : 0;
    ctx.step[d] = 1 << ctx.level[d];
    if (ctx.nb[d] && ctx.level[d] != owner.mesh_level) ctx.uniform = false;
    if (ctx.nb[d]) {
      any_negative |= ctx.nb[d]->mesh_has_negative;
      any_positive |= ctx.nb[d]->mesh_has_positive;
    }
  }
  int coarsest_step = 1;
  for (int d = 0; d < 8; ++d)
    if (ctx.nb[d]) coarsest_step = std::max(coarsest_step, ctx.step[d]);
  ctx.truncated_abs = static_cast<float>(0.99 * params_.truncation_vox * coarsest_step * params_.voxel_size_m);
  // Every value the mesher uses is a convex combination of these blocks' observed samples:
  // with one sign only, no cell can change sign.
  if (!any_negative || !any_positive) return;

  std::vector<std::pair<int, int>> intervals[3];
  for (int d = 0; d < 8; ++d) {
    if (ctx.nb[d] == nullptr) continue;
    const int step = ctx.step[d];
    const int side = kFinestSide / step;
    for (int a = 0; a < 3; ++a) {
      intervals[a].clear();
      if ((d >> a) & 1) {
        intervals[a].push_back({kBlockUnits, kBlockUnits + step});  // neighbour's low skin
      } else {
        for (int i = 0; i + 1 < side; ++i) intervals[a].push_back({step * (2 * i + 1), step * (2 * i + 3)});
        intervals[a].push_back({step * (2 * side - 1), kBlockUnits});  // own high skin
      }
    }
    for (const auto& [z0, z1] : intervals[2])
      for (const auto& [y0, y1] : intervals[1])
        for (const auto& [x0, x1] : intervals[0]) {
          const int lo[3] = {x0, y0, z0}, hi[3] = {x1, y1, z1};
          meshBox(ctx, lo, hi);
        }
  }

  // Area-weighted face normals, pointing to negative SDF (the triangles' winding).
  out->normals.assign(out->positions.size(), Eigen::Vector3f::Zero());
  for (const auto& t : out->triangles) {
    const Eigen::Vector3f n = (out->positions[t[1]] - out->positions[t[0]])
                                  .cross(out->positions[t[2]] - out->positions[t[0]]);
    for (uint32_t v : t) out->normals[v] += n;
  }
  for (Eigen::Vector3f& n : out->normals) {
    const float len = n.norm();
    n = len > 0.0f ? Eigen::Vector3f(n / len) : Eigen::Vector3f::UnitZ();
  }
}

}  // namespace stereo_fusion
