// Shared by the paging and map-store tests: a hall a camera walks along and back, and the
// map's outputs as bytes.
#pragma once
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>

#include "MeshTestSupport.h"
#include "stereo_fusion/Mapper.h"
#include "stereo_fusion/io/PlanningExport.h"
#include "stereo_fusion/planning/OccupancyGrid2D.h"

namespace stereo_fusion::test {

namespace fs = std::filesystem;

/// A hall along +x (world z up): a floor, a far wall and a row of pillars and balls, long
/// enough that a camera walking along it and back leaves space behind and comes back to it.
inline sim::AnalyticScene hall() {
  sim::AnalyticScene scene;
  scene.add(sim::makePlane({0, 0, 0}, {0, 0, 1}), {170, 160, 140});
  scene.add(sim::makePlane({0, 3.0, 0}, {0, -1, 0}), {120, 140, 190});
  for (int k = 0; k < 8; ++k) {
    scene.add(sim::makeSphere({0.9 * k, 1.8, 0.5}, 0.3), {200.0, 80.0 + 15 * k, 60.0});
    Eigen::Isometry3d T_world_box = Eigen::Isometry3d::Identity();
    T_world_box.translation() = Eigen::Vector3d(0.9 * k + 0.45, 2.4, 0.4);
    scene.add(sim::makeBox(T_world_box, {0.2, 0.2, 0.8}), {60, 160, 90});
  }
  return scene;
}

/// Camera positions along the hall and back, with random steps and a random look direction.
inline std::vector<Eigen::Isometry3d> walk(std::mt19937* rng, int frames) {
  std::uniform_real_distribution<double> step(0.12, 0.3), look(-0.6, 0.6), height(0.8, 1.2);
  std::vector<Eigen::Isometry3d> poses;
  double x = 0.0;
  for (int f = 0; f < frames; ++f) {
    x += (f < frames / 2 ? 1.0 : -1.0) * step(*rng);
    const Eigen::Vector3d eye(x, 0.0, height(*rng));
    poses.push_back(
        sim::lookAt(eye, eye + Eigen::Vector3d(look(*rng), 1.0, -0.35), Eigen::Vector3d::UnitZ()));
  }
  return poses;
}

inline MapperConfig hallConfig() {
  MapperConfig config;
  config.voxel_size_m = 0.04;
  config.max_depth_m = 4.0;
  config.num_threads = 2;
  return config;
}

inline std::string fileBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

/// Everything the map puts out, as bytes: equal outputs ⇔ equal strings.
struct Outputs {
  TriangleMesh mesh;
  std::vector<uint8_t> map_file;
  std::string esdf_ply;
  std::vector<int8_t> grid;
};

inline Outputs outputsOf(Mapper* mapper, const fs::path& scratch) {
  mapper->updateMesh();
  mapper->updatePlanning();
  Outputs out;
  out.mesh = mapper->extractMesh();
  out.map_file = mapper->encodeMap();
  std::string error;
  const fs::path esdf = scratch / "esdf.ply";
  EXPECT_TRUE(writeEsdfPly(esdf.string(), *mapper->planning(), &error)) << error;
  out.esdf_ply = fileBytes(esdf);
  out.grid = projectOccupancy(*mapper->planning(), 0.1, 1.5).cells;
  return out;
}

inline void expectSameOutputs(const Outputs& a, const Outputs& b, const std::string& what) {
  EXPECT_EQ(a.mesh.positions, b.mesh.positions) << what;
  EXPECT_EQ(a.mesh.normals, b.mesh.normals) << what;
  EXPECT_EQ(a.mesh.colors, b.mesh.colors) << what;
  EXPECT_EQ(a.mesh.triangles, b.mesh.triangles) << what;
  EXPECT_TRUE(a.map_file == b.map_file) << what << ": map files differ" << [&] {
    size_t i = 0;
    while (i < a.map_file.size() && i < b.map_file.size() && a.map_file[i] == b.map_file[i]) ++i;
    return " (first at byte " + std::to_string(i) + " of " + std::to_string(a.map_file.size()) +
           " and " + std::to_string(b.map_file.size()) + ")";
  }();
  EXPECT_TRUE(a.esdf_ply == b.esdf_ply) << what << ": esdf.ply differs";
  EXPECT_EQ(a.grid, b.grid) << what;
}

struct Scratch {
  fs::path path;
  Scratch() {
    path = fs::temp_directory_path() /
           ("sf_paging_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~Scratch() { fs::remove_all(path); }
};

/// A long session's operations on the hall: meshing and planning at cadences, a clear, and
/// (optionally) a reset, frame by frame, so that page-outs and checkpoints fall between them.
struct HallSession {
  sim::AnalyticScene scene = hall();
  std::vector<Eigen::Isometry3d> poses;
  int seed = 0;
  int mesh_every = 1;
  int plan_every = 1;
  int clear_at = -1;
  int reset_at = -1;

  /// Fuses frame f (stamped 1 + f, noise seed 7·seed + f) and runs what falls after it.
  void frame(Mapper* mapper, int f) const {
    StereoFrame frame = renderFrame(scene, qvgaCamera(), poses[f], 0.2, 7 * seed + f);
    frame.timestamp_s = 1.0 + f;
    const bool mesh_now = (f + 1) % mesh_every == 0;
    const IntegrationResult r =
        mapper->integrate(frame, mesh_now ? MeshTiming::kNow : MeshTiming::kDeferred);
    ASSERT_TRUE(r.accepted) << r.error;
    if ((f + 1) % plan_every == 0) mapper->updatePlanning();
    if (f == clear_at) {
      ASSERT_TRUE(
          mapper
              ->clearRegion(MapRegion::box({0.0, 1.5, 0.0}, {1.2, 3.2, 1.0}), MeshTiming::kDeferred)
              .accepted);
    }
    if (f == reset_at) mapper->reset();
  }
};

}  // namespace stereo_fusion::test
