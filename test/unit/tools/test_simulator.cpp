// The stereo sequence simulator: exact primitives, ground-truth mesh, scenes, trajectories,
// rendered stereo pairs, disparity models and the dataset folder it writes.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <numeric>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <set>
#include <sstream>

#include "readers/DatasetReader.h"
#include "simulator/AnalyticScene.h"
#include "simulator/DatasetWriter.h"
#include "simulator/SceneLibrary.h"
#include "simulator/StereoRenderer.h"
#include "simulator/Trajectory.h"
#include "stereo_fusion/mesh/SubMesh.h"

using namespace stereo_fusion;
using namespace stereo_fusion::sim;
namespace fs = std::filesystem;

namespace {

Eigen::Isometry3d posed(const Eigen::Vector3d& t, double angle, const Eigen::Vector3d& axis) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.rotate(Eigen::AngleAxisd(angle, axis.normalized()));
  T.translation() = t;
  return T;
}

/// Distance from `p` to the triangle (a, b, c): to its plane when the projection falls inside,
/// otherwise to the nearest of its three edges.
double pointTriangleDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                             const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d n = (b - a).cross(c - a);
  const double area2 = n.norm();
  if (area2 > 1e-18) {
    const Eigen::Vector3d un = n / area2;
    const Eigen::Vector3d q = p - un.dot(p - a) * un;
    const double wa = (b - q).cross(c - q).dot(un), wb = (c - q).cross(a - q).dot(un),
                 wc = (a - q).cross(b - q).dot(un);
    if (wa >= 0 && wb >= 0 && wc >= 0) return std::abs(un.dot(p - a));
  }
  auto segment = [&](const Eigen::Vector3d& s, const Eigen::Vector3d& e) {
    const Eigen::Vector3d d = e - s;
    const double t = std::clamp(d.dot(p - s) / std::max(d.squaredNorm(), 1e-30), 0.0, 1.0);
    return (s + t * d - p).norm();
  };
  return std::min({segment(a, b), segment(b, c), segment(c, a)});
}

double meshDistance(const TriangleMesh& m, const Eigen::Vector3d& p) {
  double best = INFINITY;
  for (const auto& t : m.triangles)
    best = std::min(best, pointTriangleDistance(p, m.positions[t[0]].cast<double>(),
                                                m.positions[t[1]].cast<double>(),
                                                m.positions[t[2]].cast<double>()));
  return best;
}

double meshArea(const TriangleMesh& m) {
  double area = 0;
  for (const auto& t : m.triangles)
    area += 0.5 * (m.positions[t[1]] - m.positions[t[0]])
                      .cast<double>()
                      .cross((m.positions[t[2]] - m.positions[t[0]]).cast<double>())
                      .norm();
  return area;
}

StereoCamera smallCamera(int width = 160, int height = 120, double fx = 131.25,
                         double baseline = 0.1) {
  return *StereoCamera::create(width, height, fx, fx, (width - 1) / 2.0, (height - 1) / 2.0,
                               baseline);
}

bool sameImage(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() &&
         std::equal(a.datastart, a.dataend, b.datastart);
}

/// A fresh, empty folder under the system temp folder, removed when the test ends.
struct TempFolder {
  fs::path path;
  explicit TempFolder(const std::string& name)
      : path(fs::temp_directory_path() / (name + "_" + std::to_string(::getpid()))) {
    fs::remove_all(path);
  }
  ~TempFolder() { fs::remove_all(path); }
};

}  // namespace

// ---------------------------------------------------------------------------------------------
// Cylinder and room primitives
// ---------------------------------------------------------------------------------------------

TEST(SimulatorPrimitives, CylinderDistanceByHand) {
  const auto cyl = makeCylinder(Eigen::Isometry3d::Identity(), 0.5, 1.0);
  EXPECT_NEAR(cyl->signedDistance({1.0, 0, 0}), 0.5, 1e-12);       // beside the side
  EXPECT_NEAR(cyl->signedDistance({0, 0, 2.0}), 1.0, 1e-12);       // above the cap
  EXPECT_NEAR(cyl->signedDistance({0, 0, 0}), -0.5, 1e-12);        // centre: nearest is the side
  EXPECT_NEAR(cyl->signedDistance({0.3, 0, 0.95}), -0.05, 1e-12);  // inside, nearest is the cap
  EXPECT_NEAR(cyl->signedDistance({0, 1.5, 3.0}), std::hypot(1.0, 2.0), 1e-12);  // beyond the rim
  // Posed: rotated 90° about x, so its axis is the world's −y axis.
  const auto lying = makeCylinder(posed({1, 2, 3}, M_PI / 2, Eigen::Vector3d::UnitX()), 0.5, 1.0);
  EXPECT_NEAR(lying->signedDistance({1, 2 + 1.5, 3}), 0.5, 1e-12);
  EXPECT_NEAR(lying->signedDistance({1, 2, 3 + 0.8}), 0.3, 1e-12);
}

TEST(SimulatorPrimitives, CylinderRaycastByHand) {
  const auto cyl = makeCylinder(Eigen::Isometry3d::Identity(), 0.5, 1.0);
  EXPECT_NEAR(cyl->raycast({0, 0, -5}, {0, 0, 1}, 1e-9), 4.0, 1e-12);    // along the axis: cap
  EXPECT_NEAR(cyl->raycast({-3, 0, 0}, {1, 0, 0}, 1e-9), 2.5, 1e-12);    // side
  EXPECT_NEAR(cyl->raycast({0, 0, 0}, {1, 0, 0}, 1e-9), 0.5, 1e-12);     // from inside: the exit
  EXPECT_NEAR(cyl->raycast({0, 0, 0.5}, {0, 0, 1}, 1e-9), 0.5, 1e-12);   // from inside, cap exit
  EXPECT_TRUE(std::isinf(cyl->raycast({0.6, 0, -5}, {0, 0, 1}, 1e-9)));  // parallel, outside
  EXPECT_TRUE(std::isinf(cyl->raycast({-3, 0, 1.2}, {1, 0, 0}, 1e-9)));  // passes above the cap
  EXPECT_TRUE(std::isinf(cyl->raycast({3, 0, 0}, {1, 0, 0}, 1e-9)));     // pointing away
  // Diagonal through the rim region: enters the side at x = -0.5 below the cap.
  const Eigen::Vector3d d = Eigen::Vector3d(1, 0, 1).normalized();
  EXPECT_NEAR(cyl->raycast({-1.5, 0, -0.5}, d, 1e-9), std::sqrt(2.0), 1e-12);
}

TEST(SimulatorPrimitives, CylinderRandomRaysHitTheSurfaceFirst) {
  const auto cyl = makeCylinder(posed({0.1, -0.2, 1.5}, 0.7, {1, 2, 3}), 0.25, 0.4);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(-0.4, 0.4);
  int hits = 0;
  for (int n = 0; n < 500; ++n) {
    const Eigen::Vector3d o(0.0, 0.0, 0.0);
    const Eigen::Vector3d dir =
        Eigen::Vector3d(0.1 + jitter(rng), -0.2 + jitter(rng), 1.5).normalized();
    const double t = cyl->raycast(o, dir, 1e-9);
    if (!std::isfinite(t)) continue;
    ++hits;
    EXPECT_NEAR(cyl->signedDistance(o + t * dir), 0.0, 1e-9);
    for (double s = 0.01; s < t - 1e-3; s += 0.01)
      EXPECT_GT(cyl->signedDistance(o + s * dir), -1e-9);
  }
  EXPECT_GT(hits, 100);
}

TEST(SimulatorPrimitives, RoomIsFreeInsideAndItsWallsAreHitFromWithin) {
  const auto room = makeRoom(posed({0, 0, 1.3}, 0.0, Eigen::Vector3d::UnitZ()), {2.5, 1.5, 1.3});
  EXPECT_NEAR(room->signedDistance({0, 0, 1.3}), 1.3, 1e-12);             // free space: positive
  EXPECT_NEAR(room->signedDistance({0, 0, -0.2}), -0.2, 1e-12);           // under the floor: solid
  EXPECT_NEAR(room->raycast({0, 0, 1.0}, {0, 0, -1}, 1e-9), 1.0, 1e-12);  // the floor
  EXPECT_NEAR(room->raycast({0, 0, 1.0}, {1, 0, 0}, 1e-9), 2.5, 1e-12);   // the +x wall
  AnalyticScene scene;
  scene.add(makeRoom(posed({0, 0, 1.3}, 0.0, Eigen::Vector3d::UnitZ()), {2.5, 1.5, 1.3}));
  scene.add(makeSphere({1, 0, 1}, 0.5));
  EXPECT_NEAR(scene.clearance({0, 0, 1}), 0.5, 1e-12);   // nearest solid: the sphere
  EXPECT_NEAR(scene.clearance({1, 0, 1}), -0.5, 1e-12);  // inside the sphere
}

// ---------------------------------------------------------------------------------------------
// Ground-truth mesh
// ---------------------------------------------------------------------------------------------

TEST(SimulatorTessellation, VerticesLieOnThePrimitivesAndTheMeshCoversThem) {
  const double e = 0.05;
  struct Case {
    const char* name;
    std::unique_ptr<Primitive> prim;
    double area_m2;
    double min_radius_m;  // smallest radius of curvature (inf when flat)
  };
  const Eigen::Isometry3d T = posed({0.3, -0.1, 1.2}, 0.5, {1, -2, 0.5});
  std::vector<Case> cases;
  cases.push_back({"sphere", makeSphere({0.3, -0.1, 1.2}, 0.3), 4 * M_PI * 0.09, 0.3});
  cases.push_back({"box", makeBox(T, {0.2, 0.13, 0.31}),
                   8 * (0.2 * 0.13 + 0.13 * 0.31 + 0.2 * 0.31), INFINITY});
  cases.push_back(
      {"room", makeRoom(T, {0.6, 0.5, 0.4}), 8 * (0.6 * 0.5 + 0.5 * 0.4 + 0.6 * 0.4), INFINITY});
  cases.push_back({"cylinder", makeCylinder(T, 0.12, 0.25),
                   2 * M_PI * 0.12 * 0.12 + 4 * M_PI * 0.12 * 0.25, 0.12});
  cases.push_back({"torus", makeTorus(T, 0.3, 0.08), 4 * M_PI * M_PI * 0.3 * 0.08, 0.08});
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    TriangleMesh mesh;
    c.prim->tessellate(&mesh, e);
    ASSERT_FALSE(mesh.empty());
    ASSERT_EQ(mesh.normals.size(), mesh.positions.size());
    ASSERT_EQ(mesh.colors.size(), mesh.positions.size());
    // On the surface up to float rounding; normals along the SDF gradient (out of the solid).
    for (size_t v = 0; v < mesh.positions.size(); ++v) {
      const Eigen::Vector3d p = mesh.positions[v].cast<double>();
      ASSERT_LT(std::abs(c.prim->signedDistance(p)), 1e-6);
      // The SDF grows along the normal (by 2δ over ±δ on a face, by δ on an edge, where
      // one side stays on the neighbouring face).
      const Eigen::Vector3d n = mesh.normals[v].cast<double>();
      const double delta = 1e-4;
      EXPECT_GT(c.prim->signedDistance(p + delta * n) - c.prim->signedDistance(p - delta * n),
                0.9 * delta);
    }
    // Triangles wound counter-clockwise seen from outside; no edge much longer than asked.
    for (const auto& t : mesh.triangles) {
      const Eigen::Vector3f face = (mesh.positions[t[1]] - mesh.positions[t[0]])
                                       .cross(mesh.positions[t[2]] - mesh.positions[t[0]]);
      EXPECT_GT(face.dot(mesh.normals[t[0]] + mesh.normals[t[1]] + mesh.normals[t[2]]), 0.0f);
      for (int k = 0; k < 3; ++k)
        EXPECT_LE((mesh.positions[t[k]] - mesh.positions[t[(k + 1) % 3]]).norm(),
                  e * std::sqrt(2.0) + 1e-6);
    }
    // Covers the surface: the area matches and every surface point is near the mesh.
    const double chord_tol =
        std::isinf(c.min_radius_m)
            ? 1e-6
            : c.min_radius_m * (1 - std::cos(M_PI / 24)) + e * e / (8 * c.min_radius_m);
    EXPECT_NEAR(meshArea(mesh), c.area_m2, 0.03 * c.area_m2);
    std::mt19937 rng(7);
    std::normal_distribution<double> g;
    int samples = 0;
    for (int n = 0; n < 2000 && samples < 150; ++n) {
      // Rays from a sphere of origins around the primitive towards its centre (for the room:
      // from its centre outwards) find surface points all over it.
      const Eigen::Vector3d dir = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
      const Eigen::Vector3d centre(0.3, -0.1, 1.2);
      const bool room = std::string(c.name) == "room";
      const Eigen::Vector3d o = room ? centre : Eigen::Vector3d(centre + 3.0 * dir);
      const Eigen::Vector3d ray =
          room ? dir
               : Eigen::Vector3d(-dir + 0.1 * Eigen::Vector3d(g(rng), g(rng), g(rng))).normalized();
      const double t = c.prim->raycast(o, ray, 1e-9);
      if (!std::isfinite(t)) continue;
      ++samples;
      EXPECT_LT(meshDistance(mesh, o + t * ray), chord_tol + 1e-6);
    }
    EXPECT_GT(samples, 100);
  }
}

TEST(SimulatorTessellation, PresetMeshesLieOnTheScenesSurfaces) {
  for (const char* name : {"room", "tabletop", "hall", "building"}) {
    const ScenePreset preset = *makePreset(name, 5);
    TriangleMesh mesh;
    preset.scene.tessellate(&mesh, 0.1);
    ASSERT_GT(mesh.triangles.size(), 1000u) << name;
    double worst = 0;
    for (const auto& p : mesh.positions)
      worst = std::max(worst, preset.scene.distanceToSurface(p.cast<double>()));
    EXPECT_LT(worst, 1e-6) << name;
    // Vertex colours come from the texture, not one flat colour per primitive.
    std::set<std::array<uint8_t, 3>> colours(mesh.colors.begin(), mesh.colors.end());
    EXPECT_GT(colours.size(), 100u) << name;
  }
}

// ---------------------------------------------------------------------------------------------
// Scenes and trajectories
// ---------------------------------------------------------------------------------------------

TEST(SimulatorScenes, SameSeedSameSceneOtherSeedOtherScene) {
  const StereoCamera camera = smallCamera();
  for (const char* name : {"room", "tabletop", "hall", "building"}) {
    SCOPED_TRACE(name);
    const ScenePreset a = *makePreset(name, 11), b = *makePreset(name, 11),
                      c = *makePreset(name, 12);
    const Eigen::Isometry3d pose =
        lookAt(a.focus_m + Eigen::Vector3d(a.orbit_radius_m, 0, a.orbit_height_m), a.focus_m);
    cv::Mat da, ca, db, cb, dc, cc;
    renderDepthAndColor(a.scene, camera, pose, &da, &ca);
    renderDepthAndColor(b.scene, camera, pose, &db, &cb);
    renderDepthAndColor(c.scene, camera, pose, &dc, &cc);
    EXPECT_TRUE(sameImage(da, db));
    EXPECT_TRUE(sameImage(ca, cb));
    EXPECT_FALSE(sameImage(ca, cc));
  }
  EXPECT_FALSE(makePreset("garden", 0).has_value());
}

TEST(SimulatorScenes, TabletopHasFourToSixObjectsOnTheTable) {
  std::set<size_t> counts;
  for (uint32_t seed = 0; seed < 30; ++seed) {
    const ScenePreset p = makeTabletopPreset(seed);
    // Room shell + table top + 4 legs, then the objects.
    const size_t objects = p.scene.size() - 6;
    EXPECT_GE(objects, 4u);
    EXPECT_LE(objects, 6u);
    counts.insert(objects);
    // Each object rests on the table top (z = 0.75): it touches that plane and does not
    // reach below it.
    for (size_t i = 6; i < p.scene.size(); ++i) {
      const Primitive& obj = p.scene.primitive(static_cast<int>(i));
      double on_top = INFINITY, below = INFINITY;
      for (double x = -0.6; x <= 0.6; x += 0.01)
        for (double y = -0.4; y <= 0.4; y += 0.01) {
          on_top = std::min(on_top, obj.signedDistance({x, y, 0.75}));
          below = std::min(below, obj.signedDistance({x, y, 0.745}));
        }
      EXPECT_NEAR(on_top, 0.0, 0.002) << "seed " << seed << " object " << i;
      EXPECT_GT(below, 0.004) << "seed " << seed << " object " << i;
    }
  }
  EXPECT_GT(counts.size(), 1u);  // the seed varies the number of objects
}

TEST(SimulatorTrajectory, OrbitCirclesTheCentreLookingAtIt) {
  OrbitParams orbit;
  orbit.centre_m = {0.5, -0.2, 0.8};
  orbit.radius_m = 1.2;
  orbit.height_m = 0.6;
  const auto poses = makeOrbit(orbit, 50, 20.0, 3);
  ASSERT_EQ(poses.size(), 50u);
  double swept = 0;
  for (size_t k = 0; k < poses.size(); ++k) {
    const Eigen::Isometry3d& T = poses[k].T_world_camera;
    EXPECT_DOUBLE_EQ(poses[k].timestamp_s, k / 20.0);
    EXPECT_NEAR((T.linear().transpose() * T.linear() - Eigen::Matrix3d::Identity()).norm(), 0,
                1e-12);
    EXPECT_NEAR(T.linear().determinant(), 1.0, 1e-12);
    const Eigen::Vector3d rel = T.translation() - orbit.centre_m;
    EXPECT_NEAR(rel.head<2>().norm(), 1.2, 0.12 + 1e-9);
    EXPECT_NEAR(rel.z(), 0.6, 0.06 + 1e-9);
    // The centre is on the optical axis, in front.
    const Eigen::Vector3d c_cam = T.inverse() * orbit.centre_m;
    EXPECT_GT(c_cam.z(), 0);
    EXPECT_NEAR(c_cam.head<2>().norm(), 0, 1e-9);
    // Image "down" (optical y) points down in the world: no roll.
    EXPECT_LT(T.linear().col(1).z(), 0);
    if (k > 0) {
      const Eigen::Vector3d a = poses[k - 1].T_world_camera.translation() - orbit.centre_m;
      swept +=
          std::abs(std::atan2(a.x() * rel.y() - a.y() * rel.x(), a.head<2>().dot(rel.head<2>())));
    }
  }
  EXPECT_NEAR(swept, 2 * M_PI * 49 / 50, 1e-6);  // one revolution over the sequence
  const auto same = makeOrbit(orbit, 50, 20.0, 3), other = makeOrbit(orbit, 50, 20.0, 4);
  EXPECT_TRUE(same[7].T_world_camera.isApprox(poses[7].T_world_camera, 0));
  EXPECT_FALSE(other[7].T_world_camera.isApprox(poses[7].T_world_camera, 1e-6));
}

TEST(SimulatorTrajectory, OdometryDriftGrowsLinearlyToTheRequestedYawAndOffset) {
  // Three frames: the first at (1, 0, 1.5), the others elsewhere; 4° and 0.15 m at the last.
  std::vector<TimedPose> truth(3);
  truth[0].T_world_camera.translation() = Eigen::Vector3d(1, 0, 1.5);
  truth[1].T_world_camera.translation() = Eigen::Vector3d(0, 1, 1.5);
  truth[2].T_world_camera.translation() = Eigen::Vector3d(-1, 0, 1.0);
  truth[2].T_world_camera.linear() =
      Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const std::vector<TimedPose> odometry = addOdometryDrift(truth, 4.0, 0.15);
  ASSERT_EQ(odometry.size(), 3u);
  EXPECT_TRUE(odometry[0].T_world_camera.isApprox(truth[0].T_world_camera, 1e-15));
  // Last frame: rotated by 4° about the vertical through (1, 0): the point (−1, 0) is 2 m from
  // it, so it moves to (1 − 2 cos 4°, −2 sin 4°), then by 0.15·(2, 1)/√5.
  const double a = 4.0 * M_PI / 180.0;
  const Eigen::Vector3d expected(1 - 2 * std::cos(a) + 0.3 / std::sqrt(5.0),
                                 -2 * std::sin(a) + 0.15 / std::sqrt(5.0), 1.0);
  EXPECT_TRUE(odometry[2].T_world_camera.translation().isApprox(expected, 1e-12));
  const Eigen::Matrix3d turn =
      odometry[2].T_world_camera.linear() * truth[2].T_world_camera.linear().transpose();
  EXPECT_NEAR(std::atan2(turn(1, 0), turn(0, 0)), a, 1e-12);
  EXPECT_NEAR(turn(2, 2), 1.0, 1e-12);  // about the vertical only
  // Halfway: half of it.
  const Eigen::Matrix3d half =
      odometry[1].T_world_camera.linear() * truth[1].T_world_camera.linear().transpose();
  EXPECT_NEAR(std::atan2(half(1, 0), half(0, 0)), a / 2, 1e-12);
}

TEST(SimulatorTrajectory, PresetPathsStayInsideTheRoomAndSeeTheScene) {
  // The disparity limit of the default SGBM range: nothing visible may be nearer than this.
  const StereoCamera camera = smallCamera(80, 60, 65.625, 0.1);
  const double min_depth_m = 525.0 * 0.1 / 128.0;
  for (const char* preset_name : {"room", "tabletop", "hall"}) {
    const ScenePreset preset = *makePreset(preset_name, 2);
    for (const char* traj : {"orbit", "walkthrough"}) {
      SCOPED_TRACE(std::string(preset_name) + " " + traj);
      std::string error;
      const auto poses = makeTrajectory(traj, preset, 60, 10.0, 2, &error);
      ASSERT_TRUE(poses.has_value()) << error;
      ASSERT_EQ(poses->size(), 60u);
      double max_step = 0, min_step = INFINITY;
      for (size_t k = 0; k < poses->size(); ++k) {
        const Eigen::Isometry3d& T = (*poses)[k].T_world_camera;
        const Eigen::Vector3d eye = T.translation();
        EXPECT_TRUE(preset.room_interior.contains(eye));
        EXPECT_GT(preset.scene.clearance(eye), 0.3);
        EXPECT_LT(T.linear().col(1).z(), 0);  // upright
        if (k > 0) {
          const Eigen::Isometry3d& P = (*poses)[k - 1].T_world_camera;
          const double step = (eye - P.translation()).norm();
          max_step = std::max(max_step, step);
          min_step = std::min(min_step, step);
          EXPECT_LT(Eigen::AngleAxisd(P.linear().transpose() * T.linear()).angle(),
                    0.25);  // smooth
        }
        // Every pixel sees a surface, none too near for the stereo range.
        if (k % 6 == 0) {
          cv::Mat depth;
          renderDepthAndColor(preset.scene, camera, T, &depth, nullptr);
          double lo, hi;
          cv::minMaxLoc(depth, &lo, &hi);
          EXPECT_GT(lo, min_depth_m);
          EXPECT_LT(hi, 8.0);
        }
      }
      EXPECT_LT(max_step, 0.3);             // at most 3 m/s at 10 Hz
      EXPECT_LT(max_step, 1.6 * min_step);  // steady speed, no jumps
      const auto again = makeTrajectory(traj, preset, 60, 10.0, 2, &error);
      const auto other = makeTrajectory(traj, preset, 60, 10.0, 3, &error);
      EXPECT_TRUE((*again)[30].T_world_camera.isApprox((*poses)[30].T_world_camera, 0));
      EXPECT_FALSE((*other)[30].T_world_camera.isApprox((*poses)[30].T_world_camera, 1e-6));
    }
  }
}

TEST(SimulatorScenes, HallOrbitSeesMostlyFarSurfaces) {
  // The far-range class: from the hall's default orbit, most of what the camera sees lies
  // 3–4.5 m away, for any seed (a 640×480, f = 576 px camera scaled down by 8).
  const StereoCamera camera = smallCamera(80, 60, 72.0, 0.12);
  for (uint32_t seed = 0; seed < 5; ++seed) {
    SCOPED_TRACE(seed);
    const ScenePreset preset = *makePreset("hall", seed);
    std::string error;
    const auto poses = makeTrajectory("orbit", preset, 12, 10.0, seed, &error);
    ASSERT_TRUE(poses.has_value()) << error;
    std::vector<float> depths;
    for (const TimedPose& pose : *poses) {
      cv::Mat depth;
      renderDepthAndColor(preset.scene, camera, pose.T_world_camera, &depth, nullptr);
      for (int v = 0; v < depth.rows; ++v)
        for (int u = 0; u < depth.cols; ++u) depths.push_back(depth.at<float>(v, u));
    }
    std::sort(depths.begin(), depths.end());
    const float p20 = depths[depths.size() / 5], median = depths[depths.size() / 2];
    EXPECT_GT(p20, 2.5f);
    EXPECT_GT(median, 3.0f);
    EXPECT_LT(median, 4.5f);
  }
}

// The two building presets: the seeds each test walks, and the rooms each has.
struct BuildingCase {
  const char* name;
  uint32_t seeds;
  size_t rooms;
};
constexpr BuildingCase kBuildings[] = {{"building", 4, 2 * kBuildingColumns},
                                       {"building_long", 1, 2 * kLongBuildingColumns}};

TEST(SimulatorScenes, BuildingRoomsAreFurnishedAndReachableThroughTheirDoorways) {
  for (const BuildingCase& building : kBuildings)
    for (uint32_t seed = 0; seed < building.seeds; ++seed) {
      SCOPED_TRACE(std::string(building.name) + " seed " + std::to_string(seed));
      const ScenePreset preset = *makePreset(building.name, seed);
      ASSERT_EQ(preset.rooms_m.size(), building.rooms);
      // Free cells at eye height (1.5 m, 0.3 m from every solid) on a 5 cm grid over the plan,
      // flooded from the tour's first point: a wall is 0.1 m thick, so the flood crosses from room
      // to room only through a doorway.
      const Eigen::AlignedBox3d& plan = preset.room_interior;
      constexpr double kCell = 0.05, kEye = 1.5;
      const int nx = static_cast<int>(plan.sizes().x() / kCell) + 1,
                ny = static_cast<int>(plan.sizes().y() / kCell) + 1;
      auto centre = [&](int i, int j) {
        return Eigen::Vector3d(plan.min().x() + i * kCell, plan.min().y() + j * kCell, kEye);
      };
      std::vector<int> state(nx * ny, 0);  // 0 solid or unvisited free, 1 free, 2 reached
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) state[j * nx + i] = preset.scene.clearance(centre(i, j)) > 0.3;
      const Eigen::Vector3d start = preset.route_m.front();
      const int si = static_cast<int>(std::lround((start.x() - plan.min().x()) / kCell)),
                sj = static_cast<int>(std::lround((start.y() - plan.min().y()) / kCell));
      ASSERT_EQ(state[sj * nx + si], 1);
      std::vector<int> stack = {sj * nx + si};
      state[stack.back()] = 2;
      while (!stack.empty()) {
        const int c = stack.back();
        stack.pop_back();
        const int i = c % nx, j = c / nx;
        for (const auto& [di, dj] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
          const int a = i + di, b = j + dj;
          if (a < 0 || b < 0 || a >= nx || b >= ny || state[b * nx + a] != 1) continue;
          state[b * nx + a] = 2;
          stack.push_back(b * nx + a);
        }
      }
      for (size_t r = 0; r < preset.rooms_m.size(); ++r) {
        SCOPED_TRACE("room " + std::to_string(r));
        const Eigen::AlignedBox3d& room = preset.rooms_m[r];
        EXPECT_TRUE(plan.contains(room));
        int reached = 0, cells = 0;
        for (int j = 0; j < ny; ++j)
          for (int i = 0; i < nx; ++i)
            if (room.contains(centre(i, j))) {
              ++cells;
              reached += state[j * nx + i] == 2;
            }
        EXPECT_GT(reached, cells / 3);  // the free middle and more, behind a doorway
        // Furniture: straight down from 2 m, a share of the floor is covered by something higher.
        int covered = 0, rays = 0;
        for (double x = room.min().x() + 0.05; x < room.max().x(); x += 0.1)
          for (double y = room.min().y() + 0.05; y < room.max().y(); y += 0.1) {
            const Hit hit = preset.scene.raycast({x, y, 2.0}, -Eigen::Vector3d::UnitZ());
            ASSERT_TRUE(std::isfinite(hit.t));
            ++rays;
            covered += hit.t < 1.99;
          }
        EXPECT_GT(covered, rays / 10);
        EXPECT_LT(covered, rays / 2);
        // Walls: the rooms beside it on its side of the corridor are out of sight from its
        // middle (a wall between them, no doorway).
        const Eigen::Vector3d middle(room.center().x(), room.center().y(), kEye);
        for (const Eigen::AlignedBox3d& other : preset.rooms_m) {
          const bool same_side = (other.center().y() > 0) == (room.center().y() > 0);
          if (&other == &room || !same_side) continue;
          const Eigen::Vector3d there(other.center().x(), other.center().y(), kEye);
          EXPECT_LT(preset.scene.raycast(middle, (there - middle).normalized()).t,
                    (there - middle).norm() / 2 + 0.1);
        }
      }
    }
}

TEST(SimulatorTrajectory, BuildingTourEntersEveryRoomAndEndsWhereItStarted) {
  // The 640×480, f = 525 px camera scaled down by 8; the default SGBM range ends at f·b/128.
  const StereoCamera camera = smallCamera(80, 60, 65.625, 0.1);
  const double min_depth_m = 525.0 * 0.1 / 128.0;
  for (const BuildingCase& building : kBuildings)
    for (uint32_t seed = 0; seed < std::min(building.seeds, 3u); ++seed) {
      SCOPED_TRACE(std::string(building.name) + " seed " + std::to_string(seed));
      const ScenePreset preset = *makePreset(building.name, seed);
      ASSERT_EQ(preset.rooms_m.size(), building.rooms);
      // ~110 frames a room at 1 m/s and 10 Hz (its loop and the corridor to the next).
      const int frames = fullTourFrames(preset, 10.0);
      EXPECT_GT(frames, 75 * static_cast<int>(building.rooms));
      EXPECT_LT(frames, 150 * static_cast<int>(building.rooms));
      std::string error;
      const auto poses = makeTrajectory("walkthrough", preset, frames, 10.0, seed, &error);
      ASSERT_TRUE(poses.has_value()) << error;
      ASSERT_EQ(poses->size(), static_cast<size_t>(frames));
      std::vector<int> room_of(frames, -1);
      double max_step = 0, min_step = INFINITY;
      std::vector<float> depths;
      for (int k = 0; k < frames; ++k) {
        const Eigen::Isometry3d& T = (*poses)[k].T_world_camera;
        const Eigen::Vector3d eye = T.translation();
        ASSERT_TRUE(preset.room_interior.contains(eye)) << k;
        ASSERT_GT(preset.scene.clearance(eye), 0.3) << k;
        EXPECT_LT(T.linear().col(1).z(), 0);  // upright
        for (size_t r = 0; r < preset.rooms_m.size(); ++r)
          if (preset.rooms_m[r].contains(eye)) room_of[k] = static_cast<int>(r);
        if (k > 0) {
          const Eigen::Isometry3d& P = (*poses)[k - 1].T_world_camera;
          const double step = (eye - P.translation()).norm();
          max_step = std::max(max_step, step);
          min_step = std::min(min_step, step);
          // No jump in the view: the corridor's U-turns at its ends (~0.5 m radius at 1 m/s,
          // 0.2 rad a frame) with the sweep and the nod on top turn at most ~0.26 rad a frame.
          EXPECT_LT(Eigen::AngleAxisd(P.linear().transpose() * T.linear()).angle(), 0.3) << k;
        }
        // Every pixel sees a surface (the building is closed).
        if (k % 10 == 0) {
          cv::Mat depth;
          renderDepthAndColor(preset.scene, camera, T, &depth, nullptr);
          for (int v = 0; v < depth.rows; ++v)
            for (int u = 0; u < depth.cols; ++u) {
              const float z = depth.at<float>(v, u);
              ASSERT_TRUE(std::isfinite(z) && z > 0) << "frame " << k;
              depths.push_back(z);
            }
        }
      }
      EXPECT_LT(max_step, 0.11);            // 1 m/s at 10 Hz
      EXPECT_LT(max_step, 1.6 * min_step);  // steady speed, no jumps
      // Mostly within the stereo range, and near enough for the finest voxels.
      std::sort(depths.begin(), depths.end());
      EXPECT_GT(depths[depths.size() / 50], min_depth_m);
      EXPECT_LT(depths[depths.size() / 2], 3.0f);
      EXPECT_LT(depths[depths.size() * 95 / 100], 8.0f);
      // The rooms in their order, each entered once; the first once more at the end.
      std::vector<int> visits;
      for (int r : room_of)
        if (r >= 0 && (visits.empty() || visits.back() != r)) visits.push_back(r);
      std::vector<int> expected(preset.rooms_m.size());
      std::iota(expected.begin(), expected.end(), 0);
      expected.push_back(0);
      EXPECT_EQ(visits, expected);
      EXPECT_EQ(room_of.front(), 0);
      EXPECT_EQ(room_of.back(), 0);
      // The loop closes: the last frame is within a step of the first, and the next lap repeats.
      const Eigen::Vector3d first = poses->front().T_world_camera.translation();
      EXPECT_LT((poses->back().T_world_camera.translation() - first).norm(), 0.101);
      const auto longer = makeTrajectory("walkthrough", preset, frames + 5, 10.0, seed, &error);
      EXPECT_LT(((*longer)[frames].T_world_camera.translation() - first).norm(), 0.101);
      const auto again = makeTrajectory("walkthrough", preset, 50, 10.0, seed, &error);
      EXPECT_TRUE((*again)[30].T_world_camera.isApprox((*poses)[30].T_world_camera, 0));
    }
}

TEST(SimulatorTrajectory, TourRefusesARouteThroughAWall) {
  AnalyticScene scene;
  scene.add(makeBox(posed({0, 0, 1}, 0, Eigen::Vector3d::UnitZ()), {0.05, 2, 1}));
  TourParams tour;
  tour.route_m = {{-1, 0, 1.5}, {1, 0.5, 1.5}, {1, -0.5, 1.5}};
  std::string error;
  EXPECT_FALSE(makeTour(scene, tour, 10, 10.0, 0, &error).has_value());
  EXPECT_NE(error.find("passes within"), std::string::npos) << error;
  tour.route_m.pop_back();
  EXPECT_FALSE(makeTour(scene, tour, 10, 10.0, 0, &error).has_value());
  EXPECT_NE(error.find("at least 3 points"), std::string::npos) << error;
}

TEST(SimulatorTrajectory, WalkthroughReportsAnImpossibleRoom) {
  AnalyticScene scene;
  WalkthroughParams walk;
  walk.free_space_m = Eigen::AlignedBox3d(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 2.5));
  std::string error;
  EXPECT_FALSE(makeWalkthrough(scene, walk, 10, 10.0, 0, &error).has_value());
  EXPECT_NE(error.find("too small"), std::string::npos) << error;
}

// ---------------------------------------------------------------------------------------------
// Stereo rendering and disparity
// ---------------------------------------------------------------------------------------------

TEST(SimulatorStereo, ExactDisparityIsFocalTimesBaselineOverDepth) {
  const ScenePreset preset = *makePreset("room", 1);
  const StereoCamera camera = smallCamera();
  StereoRenderConfig config;
  config.mode = DisparityMode::kExact;
  StereoRenderer renderer(preset.scene, camera, config);
  const Eigen::Isometry3d pose = lookAt({-1.0, -0.5, 1.4}, {1.0, 0.5, 0.6});
  const StereoView view = renderer.render(pose, 0);
  int valid = 0;
  for (int v = 0; v < view.depth_m.rows; ++v)
    for (int u = 0; u < view.depth_m.cols; ++u) {
      const float z = view.depth_m.at<float>(v, u);
      ASSERT_GT(z, 0.0f);
      EXPECT_NEAR(view.disparity_px.at<float>(v, u), camera.fx() * camera.baseline() / z, 1e-4);
      ++valid;
    }
  EXPECT_EQ(valid, 160 * 120);
  // Depth is z along the optical axis to the ray-cast surface.
  for (const auto& uv :
       {Eigen::Vector2i(80, 60), Eigen::Vector2i(3, 7), Eigen::Vector2i(150, 110)}) {
    const Eigen::Vector3d dir = Eigen::Vector3d((uv.x() - camera.cx()) / camera.fx(),
                                                (uv.y() - camera.cy()) / camera.fy(), 1)
                                    .normalized();
    const Hit hit = preset.scene.raycast(pose.translation(), pose.linear() * dir);
    EXPECT_NEAR(view.depth_m.at<float>(uv.y(), uv.x()), hit.t * dir.z(), 1e-5);
  }
}

TEST(SimulatorStereo, NoisyDisparityHasTheRequestedStatistics) {
  cv::Mat exact(300, 400, CV_32FC1, cv::Scalar(40.0f));
  exact(cv::Rect(0, 0, 400, 10)).setTo(0.0f);  // invalid pixels stay invalid
  DisparityNoiseParams noise;                  // σ 0.3 px, 1 % outliers uniform in [1, 128)
  const cv::Mat noisy = addDisparityNoise(exact, noise, 42);
  EXPECT_EQ(cv::countNonZero(noisy(cv::Rect(0, 0, 400, 10))), 0);
  double sum = 0, sum2 = 0;
  int inliers = 0, outliers = 0, valid = 0;
  for (int v = 10; v < 300; ++v)
    for (int u = 0; u < 400; ++u) {
      const double d = noisy.at<float>(v, u), e = d - 40.0;
      ++valid;
      if (std::abs(e) > 6 * noise.sigma_px) {
        ++outliers;
        EXPECT_GE(d, 1.0);
        EXPECT_LT(d, 128.0);
        continue;
      }
      ++inliers;
      sum += e;
      sum2 += e * e;
    }
  const double mean = sum / inliers, stddev = std::sqrt(sum2 / inliers - mean * mean);
  EXPECT_NEAR(mean, 0.0, 0.005);
  EXPECT_NEAR(stddev, 0.3, 0.01);
  // Outliers landing within ±1.8 px of the truth (2.8 % of [1, 128)) count as inliers here.
  EXPECT_NEAR(outliers / double(valid), 0.01 * (1 - 3.6 / 127), 0.0015);
  EXPECT_TRUE(sameImage(noisy, addDisparityNoise(exact, noise, 42)));
  EXPECT_FALSE(sameImage(noisy, addDisparityNoise(exact, noise, 43)));
}

TEST(SimulatorStereo, NoisyFramesAreReproducibleAndDifferPerFrame) {
  const ScenePreset preset = *makePreset("tabletop", 0);
  const StereoCamera camera = smallCamera();
  StereoRenderConfig config;
  config.mode = DisparityMode::kNoisy;
  config.seed = 9;
  StereoRenderer a(preset.scene, camera, config), b(preset.scene, camera, config);
  const Eigen::Isometry3d pose = lookAt({1.0, 0.5, 1.3}, preset.focus_m);
  const StereoView a3 = a.render(pose, 3);
  b.render(pose, 0);  // rendering other frames first changes nothing
  EXPECT_TRUE(sameImage(a3.disparity_px, b.render(pose, 3).disparity_px));
  EXPECT_TRUE(sameImage(a3.left_rgb, b.render(pose, 4).left_rgb));
  EXPECT_FALSE(sameImage(a3.disparity_px, b.render(pose, 4).disparity_px));
  config.seed = 10;
  StereoRenderer c(preset.scene, camera, config);
  EXPECT_FALSE(sameImage(a3.disparity_px, c.render(pose, 3).disparity_px));
}

// Matcher errors on a wall 3 m away seen from two poses 0.2 m apart, frames 0 and 1 of one
// window: about the requested share of pixels is off by 1–3 px, and where both views see the
// same surface patch they are off by the same amount (the matcher errs on the texture, not per
// view); with windows of one frame the two frames err on other patches. The Gaussian part has
// the requested σ and differs per frame.
TEST(SimulatorStereo, MatcherMismatchesAreTiedToTheSurfaceAndAgreeAcrossViews) {
  AnalyticScene scene;
  scene.add(makeBox(posed({0, 0, 3.5}, 0, Eigen::Vector3d::UnitZ()), {6, 6, 0.5}), {180, 160, 140});
  const StereoCamera camera = smallCamera(320, 240, 260.0, 0.1);
  StereoRenderConfig config;
  config.mode = DisparityMode::kExact;
  config.matcher.mismatch_fraction = 0.03;
  config.matcher.mismatch_views = 0;  // every frame in one window
  config.seed = 5;
  StereoRenderer renderer(scene, camera, config);
  const Eigen::Isometry3d first = Eigen::Isometry3d::Identity();
  const Eigen::Isometry3d second = posed({0.2, 0.0, 0}, 0, Eigen::Vector3d::UnitZ());
  const StereoView a = renderer.render(first, 0), b = renderer.render(second, 1);
  const double exact = 260.0 * 0.1 / 3.0;
  int off = 0, valid = 0, shared = 0;
  for (int v = 0; v < 240; ++v)
    for (int u = 0; u < 320; ++u) {
      const double error = a.disparity_px.at<float>(v, u) - exact;
      ++valid;
      if (std::abs(error) < 1e-3) continue;
      ++off;
      EXPECT_GE(std::abs(error), 1.0 - 1e-4);
      EXPECT_LE(std::abs(error), 3.0 + 1e-4);
      // The same surface point in the second view (0.2 m to the right: 17.3 px to the left).
      const Eigen::Vector3d p = first * camera.backProject(u, v, 3.0);
      const Eigen::Vector3d q = second.inverse() * p;
      const int u2 = static_cast<int>(std::lround(camera.fx() * q.x() / q.z() + camera.cx()));
      if (u2 < 0 || u2 >= 320 || u2 == u) continue;
      const Eigen::Vector3d p2 = second * camera.backProject(u2, v, 3.0);
      if ((p2 / 0.05).array().floor().matrix() != (p / 0.05).array().floor().matrix()) continue;
      ++shared;
      EXPECT_NEAR(b.disparity_px.at<float>(v, u2) - exact, error, 1e-4);
    }
  EXPECT_NEAR(off / double(valid), 0.03, 0.012);
  EXPECT_GT(shared, 200);

  // Windows of one frame: the same view in frames 0 and 1 errs on (nearly) disjoint pixels.
  config.matcher.mismatch_views = 1;
  StereoRenderer per_frame(scene, camera, config);
  const StereoView f0 = per_frame.render(first, 0), f1 = per_frame.render(first, 1);
  int off0 = 0, both = 0;
  for (int v = 0; v < 240; ++v)
    for (int u = 0; u < 320; ++u) {
      const bool e0 = std::abs(f0.disparity_px.at<float>(v, u) - exact) > 1e-3;
      const bool e1 = std::abs(f1.disparity_px.at<float>(v, u) - exact) > 1e-3;
      off0 += e0;
      both += e0 && e1;
    }
  EXPECT_GT(off0, 1000);
  EXPECT_LT(both, off0 / 5);

  config.matcher.mismatch_fraction = 0.0;
  config.matcher.sigma_px = 0.25;
  StereoRenderer noisy(scene, camera, config);
  const StereoView c = noisy.render(first, 0), d = noisy.render(first, 1);
  cv::Mat errors = c.disparity_px - exact;
  cv::Scalar mean, stddev;
  cv::meanStdDev(errors, mean, stddev);
  EXPECT_NEAR(mean[0], 0.0, 0.01);
  EXPECT_NEAR(stddev[0], 0.25, 0.01);
  EXPECT_FALSE(sameImage(c.disparity_px, d.disparity_px));
}

TEST(SimulatorStereo, RightImageIsTheLeftShiftedByTheDisparity) {
  // Fronto-parallel textured wall at z = 1 m; f·b/z = 100 · 0.1 / 1 = 10 px exactly.
  AnalyticScene scene;
  scene.add(makeBox(posed({0, 0, 1.5}, 0, Eigen::Vector3d::UnitZ()), {3, 3, 0.5}), {180, 160, 140});
  const StereoCamera camera = smallCamera(160, 120, 100.0, 0.1);
  const Eigen::Isometry3d pose = posed({0.2, -0.1, 0}, 0, Eigen::Vector3d::UnitZ());
  cv::Mat left, right, depth;
  renderStereoPair(scene, camera, pose, &left, &right, &depth);
  EXPECT_NEAR(depth.at<float>(60, 80), 1.0f, 1e-6f);
  cv::Scalar mean, stddev;
  cv::meanStdDev(left, mean, stddev);
  ASSERT_GT(stddev[0], 10.0);  // textured
  double sum = 0;
  int worst = 0, n = 0;
  for (int v = 0; v < 120; ++v)
    for (int u = 10; u < 160; ++u)
      for (int ch = 0; ch < 3; ++ch) {
        const int diff =
            std::abs(left.at<cv::Vec3b>(v, u)[ch] - right.at<cv::Vec3b>(v, u - 10)[ch]);
        worst = std::max(worst, diff);
        sum += diff;
        ++n;
      }
  EXPECT_LE(worst, 1);  // only float rounding of the hit point
  EXPECT_LT(sum / n, 0.05);
  // And the shift is really there: unshifted, the images differ.
  EXPECT_GT(
      cv::norm(left(cv::Rect(10, 0, 150, 120)), right(cv::Rect(10, 0, 150, 120)), cv::NORM_L1) /
          (150 * 120 * 3),
      5.0);
}

TEST(SimulatorStereo, SgbmOnASlantedPlaneIsSubpixelAccurate) {
  // A textured plane slanted 35° about the vertical axis: true disparities 11–23 px.
  AnalyticScene scene;
  scene.add(makeBox(posed({0, 0, 1.9}, 35 * M_PI / 180, Eigen::Vector3d::UnitY()), {4, 4, 0.2}),
            {200, 190, 170});
  const StereoCamera camera = smallCamera(320, 240, 262.5, 0.1);
  StereoRenderConfig config;
  config.mode = DisparityMode::kSgbm;
  config.sgbm.num_disparities = 48;
  StereoRenderer renderer(scene, camera, config);
  const StereoView view = renderer.render(Eigen::Isometry3d::Identity(), 0);
  const cv::Mat truth = disparityFromDepth(view.depth_m, camera);
  std::vector<double> errors;
  int considered = 0;
  for (int v = 0; v < 240; ++v)
    for (int u = config.sgbm.num_disparities; u < 320; ++u) {
      ++considered;
      const float d = view.disparity_px.at<float>(v, u);
      if (d > 0) errors.push_back(std::abs(d - truth.at<float>(v, u)));
    }
  ASSERT_FALSE(errors.empty());
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  EXPECT_LT(errors[errors.size() / 2], 0.5);
  EXPECT_GT(errors.size() / double(considered), 0.8);
  // Nothing left of the search range can be matched.
  EXPECT_EQ(cv::countNonZero(view.disparity_px(cv::Rect(0, 0, 40, 240))), 0);
}

// ---------------------------------------------------------------------------------------------
// Dataset folder
// ---------------------------------------------------------------------------------------------

TEST(SimulatorDataset, DisparityEncodingFollowsKitti) {
  cv::Mat d(1, 8, CV_32FC1);
  const float values[8] = {0.0f, -1.0f, NAN, INFINITY, 1.0f / 256, 17.3f, 255.99f, 256.5f};
  std::copy(values, values + 8, d.ptr<float>());
  const cv::Mat png = encodeDisparityPng(d);
  ASSERT_EQ(png.type(), CV_16UC1);
  const uint16_t expected[8] = {
      0, 0, 0, 0, 1, static_cast<uint16_t>(std::lround(17.3f * 256.0)), 65533, 0};
  for (int i = 0; i < 8; ++i) EXPECT_EQ(png.at<uint16_t>(0, i), expected[i]) << values[i];
  EXPECT_EQ(frameStem(0), "000000");
  EXPECT_EQ(frameStem(123456), "123456");
  EXPECT_EQ(exactDecimal(0.1), "0.1");
  EXPECT_EQ(std::stod(exactDecimal(M_PI)), M_PI);
}

TEST(SimulatorDataset, WritesTheFolderTheReaderReads) {
  TempFolder tmp("stereo_fusion_sim_dataset");
  const ScenePreset preset = *makePreset("tabletop", 4);
  const StereoCamera camera = smallCamera();
  std::string error;
  const auto poses = makeTrajectory("orbit", preset, 3, 10.0, 4, &error);
  ASSERT_TRUE(poses.has_value());
  StereoRenderConfig config;
  config.mode = DisparityMode::kNoisy;
  StereoRenderer renderer(preset.scene, camera, config);
  std::vector<StereoView> views;
  {
    auto writer = DatasetWriter::create(tmp.path.string(), camera, &error);
    ASSERT_TRUE(writer) << error;
    for (size_t k = 0; k < 3; ++k) {
      views.push_back(renderer.render((*poses)[k].T_world_camera, k));
      ASSERT_TRUE(writer->writeFrame(k, (*poses)[k].timestamp_s, (*poses)[k].T_world_camera,
                                     views[k].disparity_px, views[k].left_rgb, views[k].right_rgb,
                                     &error))
          << error;
    }
    EXPECT_FALSE(writer->writeFrame(7, 0.7, Eigen::Isometry3d::Identity(), views[0].disparity_px,
                                    views[0].left_rgb, views[0].right_rgb,
                                    &error));  // out of order
    TriangleMesh mesh;
    preset.scene.tessellate(&mesh, 0.1);
    ASSERT_TRUE(writer->writeGroundTruthMesh(mesh, &error)) << error;
  }
  for (const char* f : {"calibration.yaml", "poses.txt", "gt_mesh.ply", "disparity/000000.png",
                        "disparity/000002.png", "color/000001.png", "right/000002.png"})
    EXPECT_TRUE(fs::is_regular_file(tmp.path / f)) << f;
  EXPECT_FALSE(fs::exists(tmp.path / "disparity/000003.png"));
  std::ifstream poses_file(tmp.path / "poses.txt");
  std::string line;
  int lines = 0;
  while (std::getline(poses_file, line)) {
    std::istringstream fields(line);
    std::vector<double> values{std::istream_iterator<double>(fields), {}};
    EXPECT_EQ(values.size(), 8u) << line;
    ++lines;
  }
  EXPECT_EQ(lines, 3);

  // PNGs round-trip: the exact uint16 values, and colour in the right channel order.
  for (size_t k = 0; k < 3; ++k) {
    const std::string stem = frameStem(k) + ".png";
    const cv::Mat d16 = cv::imread((tmp.path / "disparity" / stem).string(), cv::IMREAD_UNCHANGED);
    EXPECT_TRUE(sameImage(d16, encodeDisparityPng(views[k].disparity_px)));
    cv::Mat rgb;
    cv::cvtColor(cv::imread((tmp.path / "color" / stem).string(), cv::IMREAD_COLOR), rgb,
                 cv::COLOR_BGR2RGB);
    EXPECT_TRUE(sameImage(rgb, views[k].left_rgb));
    cv::cvtColor(cv::imread((tmp.path / "right" / stem).string(), cv::IMREAD_COLOR), rgb,
                 cv::COLOR_BGR2RGB);
    EXPECT_TRUE(sameImage(rgb, views[k].right_rgb));
  }

  // The package's reader sees the same camera, poses, disparity and colour.
  const auto reader = DatasetReader::open(tmp.path.string(), &error);
  ASSERT_TRUE(reader.has_value()) << error;
  ASSERT_EQ(reader->size(), 3u);
  EXPECT_FALSE(reader->usesSgbm());
  EXPECT_FALSE(reader->groundTruthMeshPath().empty());
  EXPECT_EQ(reader->camera().fx(), camera.fx());
  EXPECT_EQ(reader->camera().cx(), camera.cx());
  EXPECT_EQ(reader->camera().baseline(), camera.baseline());
  EXPECT_EQ(reader->camera().width(), 160);
  for (size_t k = 0; k < 3; ++k) {
    StereoFrame frame;
    ASSERT_TRUE(reader->load(k, &frame, &error)) << error;
    EXPECT_DOUBLE_EQ(frame.timestamp_s, (*poses)[k].timestamp_s);
    EXPECT_TRUE(frame.T_world_camera.isApprox((*poses)[k].T_world_camera, 1e-12));
    EXPECT_TRUE(sameImage(frame.color, views[k].left_rgb));
    double worst = 0;
    for (int v = 0; v < 120; ++v)
      for (int u = 0; u < 160; ++u)
        worst = std::max(worst, double(std::abs(frame.disparity_px.at<float>(v, u) -
                                                views[k].disparity_px.at<float>(v, u))));
    EXPECT_LE(worst, 0.5 / 256 + 1e-6);
  }

  // Rewriting a shorter sequence into the same folder leaves no stale frames behind.
  {
    auto writer = DatasetWriter::create(tmp.path.string(), camera, &error);
    ASSERT_TRUE(writer) << error;
    ASSERT_TRUE(writer->writeFrame(0, 0.0, (*poses)[0].T_world_camera, views[0].disparity_px,
                                   views[0].left_rgb, views[0].right_rgb, &error));
  }
  EXPECT_FALSE(fs::exists(tmp.path / "disparity/000001.png"));
  EXPECT_FALSE(fs::exists(tmp.path / "gt_mesh.ply"));
  EXPECT_EQ(DatasetReader::open(tmp.path.string(), &error)->size(), 1u);
}

TEST(SimulatorDataset, RefusesAFolderThatIsNotADataset) {
  TempFolder tmp("stereo_fusion_sim_notadataset");
  fs::create_directories(tmp.path);
  std::ofstream(tmp.path / "notes.txt") << "precious";
  std::string error;
  EXPECT_EQ(DatasetWriter::create(tmp.path.string(), smallCamera(), &error), nullptr);
  EXPECT_NE(error.find("not a dataset"), std::string::npos) << error;
  EXPECT_TRUE(fs::exists(tmp.path / "notes.txt"));
}
