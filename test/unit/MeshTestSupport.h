#pragma once
// Helpers for the meshing tests: objects fused from views all around, and mesh topology checks.

#include <Eigen/Geometry>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <set>

#include "TestSupport.h"
#include "stereo_fusion/mesh/MeshStore.h"

namespace stereo_fusion::test {

inline StereoCamera qvgaCamera() {
  return *StereoCamera::create(320, 240, 262.5, 262.5, 159.5, 119.5, 0.1);
}

/// Camera poses on a sphere of `radius` around `centre`, looking at it (Fibonacci lattice).
/// A floor at y = 0.3 (y down) with a sphere 1.2 m ahead: the small scene of the reader, bag,
/// bad-input and map-file tests.
inline sim::AnalyticScene floorAndSphere() {
  sim::AnalyticScene scene;
  scene.add(sim::makePlane({0, 0.3, 0}, {0, -1, 0}), {180, 160, 120});
  scene.add(sim::makeSphere({0.05, 0.1, 1.2}, 0.2), {200, 60, 60});
  return scene;
}

/// View i of floorAndSphere(): the camera steps 10 cm along x, looking at the sphere.
inline Eigen::Isometry3d floorAndSphereView(int i) {
  return sim::lookAt({-0.15 + 0.1 * i, -0.2, 0.0}, {0.05, 0.1, 1.2}, -Eigen::Vector3d::UnitY());
}

/// floorAndSphere() seen from floorAndSphereView(i), stamped `timestamp_s`.
inline StereoFrame floorAndSphereFrame(int i, double timestamp_s) {
  StereoFrame f = renderFrame(floorAndSphere(), qvgaCamera(), floorAndSphereView(i));
  f.timestamp_s = timestamp_s;
  return f;
}

/// The texture tests' configuration: patches on, no histogram filter.
/// A mapper that fused `frames` noisy views of the floor and sphere (stamped 1, 2, ... s).
inline std::unique_ptr<Mapper> fusedMapper(int frames, MapperConfig config = {}) {
  auto mapper = std::make_unique<Mapper>(config);
  const sim::AnalyticScene scene = floorAndSphere();
  for (int i = 0; i < frames; ++i) {
    StereoFrame f = renderFrame(scene, qvgaCamera(), floorAndSphereView(i), 0.2, i);
    f.timestamp_s = 1.0 + i;
    EXPECT_TRUE(mapper->integrate(f).accepted);
  }
  return mapper;
}

inline MapperConfig texturedConfig() {
  MapperConfig c;
  c.texture = TextureMode::kPatches;
  c.histogram_min_points = 0;
  return c;
}

/// A camera pose at `eye` looking at `target`, image y down.
inline Eigen::Isometry3d lookFrom(const Eigen::Vector3d& eye, const Eigen::Vector3d& target) {
  return sim::lookAt(eye, target, -Eigen::Vector3d::UnitY());
}

/// A wall facing the camera at z = 1.5 m with the simulator's procedural texture.
inline sim::AnalyticScene wallScene() {
  sim::AnalyticScene scene;
  scene.add(sim::makePlane({0, 0, 1.5}, {0, 0, -1}), {200, 170, 120});
  return scene;
}

/// The whole file at `path` (empty if unreadable).
inline std::vector<uint8_t> readBytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::vector<uint8_t>((std::istreambuf_iterator<char>(f)),
                              std::istreambuf_iterator<char>());
}

/// Replaces the file at `path` by `bytes`.
inline void writeBytes(const std::string& path, const std::vector<uint8_t>& bytes) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

inline std::vector<Eigen::Isometry3d> viewsAround(const Eigen::Vector3d& centre, double radius,
                                                  int n) {
  std::vector<Eigen::Isometry3d> poses;
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double y = 1.0 - 2.0 * (i + 0.5) / n;
    const double r = std::sqrt(1.0 - y * y);
    const Eigen::Vector3d dir(r * std::cos(golden * i), y, r * std::sin(golden * i));
    poses.push_back(
        sim::lookAt(centre + radius * dir, centre, Eigen::Vector3d(0.3, 1.0, 0.2).normalized()));
  }
  return poses;
}

/// Fuses `scene` from `poses` (meshing off) and returns the mapper.
inline std::unique_ptr<Mapper> fuseViews(const sim::AnalyticScene& scene,
                                         const std::vector<Eigen::Isometry3d>& poses,
                                         MapperConfig config = {}) {
  config.mesh_enabled = false;
  config.histogram_min_points = 0;
  auto mapper = std::make_unique<Mapper>(config);
  for (const auto& pose : poses) {
    const IntegrationResult r = mapper->integrate(renderFrame(scene, qvgaCamera(), pose));
    if (!r.accepted) throw std::runtime_error(r.error);
  }
  return mapper;
}

/// A map holding the exact SDF of `scene` (our sign: negative outside the solids, in free
/// space) at `level_of(key)` only, in every block within `margin_m` of the scene's surface
/// inside `bounds`: fully observed data, so any hole in its mesh is the mesher's fault.
inline void fillAnalytic(BlockOctree* map, const sim::AnalyticScene& scene,
                         const Eigen::AlignedBox3d& bounds, double margin_m,
                         const std::function<int(const BlockKey&)>& level_of) {
  const BlockKey lo = map->keyForPoint(bounds.min()), hi = map->keyForPoint(bounds.max());
  const double bs = map->blockSize();
  for (int z = lo.z; z <= hi.z; ++z)
    for (int y = lo.y; y <= hi.y; ++y)
      for (int x = lo.x; x <= hi.x; ++x) {
        const BlockKey key{x, y, z};
        const Eigen::Vector3d centre = map->blockOrigin(key) + Eigen::Vector3d::Constant(bs / 2);
        if (scene.distanceToSurface(centre) > margin_m + bs) continue;
        VoxelBlock* b = map->findOrAllocate(key);
        const int level = level_of(key);
        const int side = levelSide(level);
        const double h = bs / side;
        for (int k = 0; k < side; ++k)
          for (int j = 0; j < side; ++j)
            for (int i = 0; i < side; ++i) {
              const Eigen::Vector3d p =
                  map->blockOrigin(key) + Eigen::Vector3d(i + 0.5, j + 0.5, k + 0.5) * h;
              double inside = INFINITY;  // most negative primitive SDF = deepest inside
              for (size_t s = 0; s < scene.size(); ++s)
                inside = std::min(inside, scene.primitive(static_cast<int>(s)).signedDistance(p));
              Voxel& v = b->writableAt(level, i, j, k);
              v.sdf_m = static_cast<float>(-inside);
              v.weight = 1.0f;
            }
      }
}

/// Topology of a welded mesh: directed edges must each appear once with their reverse once.
struct Topology {
  size_t triangles = 0;
  size_t vertices = 0;
  size_t boundary_edges = 0;  ///< directed edges without a reverse
  size_t overused_edges = 0;  ///< directed edges used more than once (overlaps, bad winding)
  size_t degenerate_triangles = 0;
  bool watertight() const {
    return triangles > 0 && boundary_edges == 0 && overused_edges == 0 && degenerate_triangles == 0;
  }
};

inline Topology topology(const TriangleMesh& mesh) {
  Topology t;
  t.triangles = mesh.triangles.size();
  t.vertices = mesh.positions.size();
  std::map<std::pair<uint32_t, uint32_t>, int> directed;
  for (const auto& tri : mesh.triangles) {
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) ++t.degenerate_triangles;
    for (int k = 0; k < 3; ++k) ++directed[{tri[k], tri[(k + 1) % 3]}];
  }
  for (const auto& [edge, count] : directed) {
    if (count > 1) ++t.overused_edges;
    if (directed.find({edge.second, edge.first}) == directed.end()) ++t.boundary_edges;
  }
  return t;
}

inline std::string describe(const Topology& t) {
  return std::to_string(t.triangles) + " triangles, " + std::to_string(t.vertices) + " vertices, " +
         std::to_string(t.boundary_edges) + " boundary edges, " + std::to_string(t.overused_edges) +
         " over-used edges, " + std::to_string(t.degenerate_triangles) + " degenerate";
}

/// Every triangle of every submesh as three position triples, rotated to start at the
/// smallest vertex (winding kept): equal sets ⇔ same triangles up to vertex order.
inline std::map<BlockKey, std::multiset<std::array<float, 9>>> triangleSets(
    const MeshStore& store) {
  std::map<BlockKey, std::multiset<std::array<float, 9>>> out;
  for (const auto& [key, mesh] : store.submeshes()) {
    auto& set = out[key];
    for (const auto& tri : mesh.triangles) {
      std::array<std::array<float, 3>, 3> v;
      for (int k = 0; k < 3; ++k)
        v[k] = {mesh.positions[tri[k]].x(), mesh.positions[tri[k]].y(), mesh.positions[tri[k]].z()};
      int first = 0;
      for (int k = 1; k < 3; ++k)
        if (v[k] < v[first]) first = k;
      std::array<float, 9> flat;
      for (int k = 0; k < 3; ++k)
        for (int c = 0; c < 3; ++c) flat[3 * k + c] = v[(first + k) % 3][c];
      set.insert(flat);
    }
  }
  return out;
}

/// The mesh `mapper` keeps equals a from-scratch extraction of its map.
inline void expectMeshEqualsRebuild(const Mapper& mapper) {
  const MapperConfig& config = mapper.config();
  MeshStore batch(
      MeshingParams{config.voxel_size_m, config.truncation_vox, config.mesh_level_min_coverage});
  ThreadPool pool(2);
  batch.rebuild(mapper.tsdf(), &pool);
  EXPECT_TRUE(triangleSets(mapper.mesh()) == triangleSets(batch))
      << "incremental mesh differs from a rebuild";
}

}  // namespace stereo_fusion::test
