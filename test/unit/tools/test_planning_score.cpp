// The planning report of stereo_fusion_evaluate_esdf: the ground truth read as solids, the ESDF's
// figures a planner meets (near-surface errors, phantom occupied cells, free cells inside a
// solid) and the occupancy map's precision and wall recall, all on hand-placed cells.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "evaluator/OccupancyMapFile.h"
#include "evaluator/OccupancyScore.h"
#include "evaluator/PlanningScore.h"
#include "evaluator/SolidTruth.h"
#include "simulator/AnalyticScene.h"

namespace stereo_fusion::eval {
namespace {

using Eigen::Vector3d;

/// Appends the quad a, b, c, d (counter-clockwise seen from where its normal points).
void addQuad(TriangleMesh* mesh, const Vector3d& a, const Vector3d& b, const Vector3d& c,
             const Vector3d& d) {
  const uint32_t i = static_cast<uint32_t>(mesh->positions.size());
  for (const Vector3d& p : {a, b, c, d}) mesh->positions.push_back(p.cast<float>());
  mesh->triangles.push_back({i, i + 1, i + 2});
  mesh->triangles.push_back({i, i + 2, i + 3});
}

/// The solid box [0, 2] × [0, 2] × [0, 1], faces wound with their normals out of it.
TriangleMesh boxMesh() {
  TriangleMesh m;
  const double x = 2, y = 2, z = 1;
  addQuad(&m, {0, 0, z}, {x, 0, z}, {x, y, z}, {0, y, z});  // top, +z
  addQuad(&m, {0, 0, 0}, {0, y, 0}, {x, y, 0}, {x, 0, 0});  // bottom, −z
  addQuad(&m, {x, 0, 0}, {x, y, 0}, {x, y, z}, {x, 0, z});  // +x
  addQuad(&m, {0, 0, 0}, {0, 0, z}, {0, y, z}, {0, y, 0});  // −x
  addQuad(&m, {0, y, 0}, {0, y, z}, {x, y, z}, {x, y, 0});  // +y
  addQuad(&m, {0, 0, 0}, {x, 0, 0}, {x, 0, z}, {0, 0, z});  // −y
  return m;
}

TEST(PlanningScoreSolidTruth, NegativeInsideTheBoxPositiveOutside) {
  const SolidTruth truth(boxMesh());
  EXPECT_NEAR(truth.signedDistance({1, 1, 0.7}), -0.3, 1e-6);    // under the top
  EXPECT_NEAR(truth.signedDistance({0.3, 1, 0.5}), -0.3, 1e-6);  // inside the −x face
  EXPECT_NEAR(truth.signedDistance({1, 1, 1.3}), 0.3, 1e-6);
  EXPECT_NEAR(truth.signedDistance({3, 1, 0.5}), 1.0, 1e-6);
  EXPECT_NEAR(truth.signedDistance({-0.5, -0.5, 0.5}), std::sqrt(0.5), 1e-6);  // off an edge
  EXPECT_NEAR(truth.signedDistance({3, 3, 2}), std::sqrt(3.0), 1e-6);          // off a corner
  EXPECT_TRUE(std::isinf(SolidTruth(TriangleMesh{}).signedDistance({0, 0, 0})));
}

// The simulator's gt_mesh.ply winding (normals out of the solid; a room's into the room) gives
// the primitives' own signed distances.
TEST(PlanningScoreSolidTruth, AgreesWithTheSimulatorsPrimitives) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.rotate(Eigen::AngleAxisd(0.4, Vector3d::UnitZ()));
  pose.translation() = Vector3d(0.5, -0.2, 0.4);
  const auto box = sim::makeBox(pose, {0.6, 0.3, 0.4});
  const auto room =
      sim::makeRoom(Eigen::Isometry3d(Eigen::Translation3d(0, 0, 1.2)), {2.0, 1.5, 1.2});
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  // Points around each: the box is ~15 % of its region, the room ~50 % of its.
  const struct {
    const sim::Primitive* primitive;
    Vector3d centre, half;
  } cases[] = {{box.get(), pose.translation(), {1.0, 0.6, 0.8}},
               {room.get(), {0, 0, 1.2}, {2.5, 2.0, 1.5}}};
  for (const auto& [primitive, centre, half] : cases) {
    TriangleMesh mesh;
    primitive->tessellate(&mesh, 0.3);
    const SolidTruth truth(mesh);
    int inside = 0;
    for (int i = 0; i < 300; ++i) {
      const Vector3d p = centre + half.cwiseProduct(Vector3d(u(rng), u(rng), u(rng)));
      const double expected = primitive->signedDistance(p);
      EXPECT_NEAR(truth.signedDistance(p), expected, 1e-5) << p.transpose();
      inside += expected < 0;
    }
    EXPECT_GT(inside, 20);  // both sides were tried
  }
}

/// The hand-placed cells around the box of boxMesh(); see ScoresHandPlacedCells.
EsdfCells handPlacedCells() {
  EsdfCells cells;
  const auto free_cell = [&](const Vector3d& p, double esdf_m) {
    cells.free_centres.push_back(p);
    cells.free_distances_m.push_back(esdf_m);
  };
  // Above the top's middle the truth is z − 1: truths 0.2, 0.3, ..., 1.2 with ESDF = truth − e
  // (e > 0: the ESDF reads closer than the truth).
  const double e[11] = {0.01, 0.02, 0.03, 0.04, 0.05, -0.06, 0.07, 0.15, 0.2, -0.3, 0.5};
  for (int k = 0; k < 11; ++k) {
    const double truth = 0.2 + 0.1 * k;
    free_cell({1, 1, 1 + truth}, truth - e[k]);
  }
  free_cell({1, 1, 1.05}, 0.05);                      // truth 0.05: below the near band
  free_cell({1, 1, 2.7}, 1.7);                        // truth 1.7: above it
  free_cell({1, 1, 0.7}, 0.3);                        // inside the box (−0.3), reads clear
  free_cell({1.5, 1, 0.4}, 0.25);                     // inside (−0.4), reads clear
  free_cell({0.3, 1, 0.5}, 0.1);                      // inside (−0.3), below the clear threshold
  for (const Vector3d& p : {Vector3d(1, 1, 1.02),     // truth 0.02: on the surface
                            Vector3d(1, 1, 0.95),     // −0.05: inside
                            Vector3d(1, 1, 1.11),     // 0.11: just short of a phantom
                            Vector3d(1, 1, 1.3),      // 0.3: phantom
                            Vector3d(3, 1, 0.5),      // 1.0: phantom
                            Vector3d(1, -0.2, 0.2)})  // 0.2 off the −y face: phantom
    cells.occupied_centres.push_back(p);
  return cells;
}

TEST(PlanningScoreEsdf, ScoresHandPlacedCells) {
  const SolidTruth truth(boxMesh());
  const auto signed_truth = [&](const Vector3d& p) { return truth.signedDistance(p); };
  const PlanningScore s = scorePlanning(handPlacedCells(), 2.0, signed_truth);
  // Near cells: the eleven of truth 0.2–1.2. |errors| sorted: 0.01 0.02 0.03 0.04 0.05 0.06 0.07
  // 0.15 0.2 0.3 0.5; nearest rank: median = #5 (0-based) 0.06, p90 = #round(9.0) 0.3.
  EXPECT_EQ(s.near_cells, 11u);
  EXPECT_NEAR(s.near_median_m, 0.06, 1e-6);
  EXPECT_NEAR(s.near_p90_m, 0.3, 1e-6);
  EXPECT_EQ(s.near_too_close, 3u);  // e = 0.15, 0.2, 0.5; e = −0.3 reads farther, not closer
  // Phantoms: truths 0.3, 1.0, 0.2 at z 1.3, 0.5, 0.2 — medians 0.3 and 0.5.
  EXPECT_EQ(s.occupied_cells, 6u);
  EXPECT_EQ(s.phantom_cells, 3u);
  EXPECT_NEAR(s.phantom_median_distance_m, 0.3, 1e-6);
  EXPECT_NEAR(s.phantom_median_z_m, 0.5, 1e-6);
  // ESDF ≥ 0.2: ten near cells (not the first, 0.19), the one of truth 1.7 and two inside.
  EXPECT_EQ(s.clear_cells, 13u);
  EXPECT_EQ(s.clear_inside_solid, 2u);
  EXPECT_NE(s.describe().find("phantom occupied (>= 12 cm in free space): 3 of 6 (50.0 %)"),
            std::string::npos)
      << s.describe();
}

TEST(PlanningScoreEsdf, SplitsOffTheNearCellsWhoseNearestSurfaceWasSeen) {
  const SolidTruth truth(boxMesh());
  const auto signed_truth = [&](const Vector3d& p) { return truth.signedDistance(p); };
  // "Seen": the near cells of truth 0.2–0.7 (z ≤ 1.7), |errors| 0.01 … 0.06; nearest rank of
  // six: median = #round(2.5) = #3 0.04, p90 = #round(4.5) = #5 0.06.
  const auto seen = [](const Vector3d& p) { return p.z() <= 1.75; };
  const PlanningScore s = scorePlanning(handPlacedCells(), 2.0, signed_truth, {}, seen);
  EXPECT_EQ(s.near_cells, 11u);
  EXPECT_EQ(s.near_seen_cells, 6u);
  EXPECT_NEAR(s.near_seen_median_m, 0.04, 1e-6);
  EXPECT_NEAR(s.near_seen_p90_m, 0.06, 1e-6);
  EXPECT_NE(s.describe().find("whose nearest true surface was seen: 6 cells (54.5 %), median "
                              "4.0 cm, p90 6.0 cm"),
            std::string::npos)
      << s.describe();
  // Without the predicate nothing is split off, and the report says nothing of it.
  const PlanningScore plain = scorePlanning(handPlacedCells(), 2.0, signed_truth);
  EXPECT_EQ(plain.near_seen_cells, 0u);
  EXPECT_EQ(plain.describe().find("was seen"), std::string::npos);
}

TEST(PlanningScoreEsdf, CapsTheEsdfAndSkipsTruthsBeyondTheMax) {
  const SolidTruth truth(boxMesh());
  EsdfCells cells;
  cells.free_centres = {{1, 1, 1.5}, {1, 1, 1.9}, {1, 1, 2.2}};  // truths 0.5, 0.9, 1.2
  cells.free_distances_m = {0.5, 3.0, 1.0};
  const PlanningScore s =
      scorePlanning(cells, 1.0, [&](const Vector3d& p) { return truth.signedDistance(p); });
  // 1.2 is beyond the max; 3.0 reads as 1.0: errors 0 and 0.1.
  EXPECT_EQ(s.near_cells, 2u);
  EXPECT_NEAR(s.near_median_m, 0.1, 1e-6);  // nearest rank of two: the second
  EXPECT_EQ(s.near_too_close, 0u);
}

// ---------------------------------------------------------------------------------------------
// Occupancy map
// ---------------------------------------------------------------------------------------------

/// Writes `rows` (top row first, as the image holds them: 'O' occupied 0, 'F' free 254,
/// 'U' unknown 205) as occupancy.pgm + occupancy.yaml the way io/PlanningExport does.
std::string writeMap(const std::string& dir, const std::vector<std::string>& rows, double res,
                     int negate = 0) {
  std::filesystem::create_directories(dir);
  std::ofstream pgm(dir + "/occupancy.pgm", std::ios::binary);
  pgm << "P5\n" << rows[0].size() << " " << rows.size() << "\n255\n";
  for (const std::string& row : rows)
    for (char c : row) pgm.put(static_cast<char>(c == 'O' ? 0 : (c == 'F' ? 254 : 205)));
  std::ofstream yaml(dir + "/occupancy.yaml");
  yaml << "image: occupancy.pgm\nresolution: " << res
       << "\norigin: [0.0, 0.0, 0.0]\nnegate: " << negate
       << "\noccupied_thresh: 0.65\nfree_thresh: 0.196\nmode: trinary\n";
  return dir + "/occupancy.yaml";
}

TEST(PlanningScoreOccupancy, ReadsTheMapAsMapServerDoes) {
  const std::string dir = ::testing::TempDir() + "planning_score_read";
  OccupancyMap map;
  std::string error;
  ASSERT_TRUE(readOccupancyMap(writeMap(dir, {"OFU", "UUF"}, 0.05), &map, &error)) << error;
  EXPECT_EQ(map.width, 3);
  EXPECT_EQ(map.height, 2);
  EXPECT_DOUBLE_EQ(map.resolution_m, 0.05);
  // Row 0 is the image's bottom row.
  EXPECT_EQ(map.at(0, 1), OccupancyMap::kOccupied);
  EXPECT_EQ(map.at(1, 1), OccupancyMap::kFree);
  EXPECT_EQ(map.at(2, 1), OccupancyMap::kUnknown);
  EXPECT_EQ(map.at(0, 0), OccupancyMap::kUnknown);
  EXPECT_EQ(map.at(2, 0), OccupancyMap::kFree);
  // negate: 1 reads value / 255 as the occupancy: 0 free, 254 and even 205 (0.80) occupied.
  ASSERT_TRUE(readOccupancyMap(writeMap(dir, {"OFU", "UUF"}, 0.05, 1), &map, &error)) << error;
  EXPECT_EQ(map.at(0, 1), OccupancyMap::kFree);
  EXPECT_EQ(map.at(1, 1), OccupancyMap::kOccupied);
  EXPECT_EQ(map.at(2, 1), OccupancyMap::kOccupied);
  EXPECT_FALSE(readOccupancyMap(dir + "/missing.yaml", &map, &error));
}

// 8 × 7 pixels of 8 cm from (0, 0); the truth: a wall x = 0.20 (column 2) from y = −0.10 to 0.55
// (rows −2..6: two past the map's bottom edge), a table top at z 0.5 over x 0.52–0.60,
// y 0–0.04, and a wall x = 0.60 above the band (z 1.6–2) over y 0.20–0.30.
TEST(PlanningScoreOccupancy, PrecisionAndWallRecallByHand) {
  TriangleMesh truth;
  addQuad(&truth, {0.2, -0.10, 0}, {0.2, 0.55, 0}, {0.2, 0.55, 2}, {0.2, -0.10, 2});
  addQuad(&truth, {0.52, 0, 0.5}, {0.60, 0, 0.5}, {0.60, 0.04, 0.5}, {0.52, 0.04, 0.5});
  addQuad(&truth, {0.6, 0.2, 1.6}, {0.6, 0.3, 1.6}, {0.6, 0.3, 2.0}, {0.6, 0.2, 2.0});
  addQuad(&truth, {-1, -1, 0}, {2, -1, 0}, {2, 2, 0}, {-1, 2, 0});  // the floor, below the band
  const std::string dir = ::testing::TempDir() + "planning_score_grid";
  OccupancyMap map;
  std::string error;
  ASSERT_TRUE(readOccupancyMap(writeMap(dir,
                                        {"UUUUUUUU",   // y = 6
                                         "UUUUUUUU",   // 5
                                         "UUUUUUUU",   // 4
                                         "UUUUUUUO",   // 3
                                         "FFFFFFFF",   // 2
                                         "FFOFFFFF",   // 1
                                         "FOFFFUOF"},  // 0
                                        0.08),
                               &map, &error))
      << error;
  const OccupancyScore s = scoreOccupancy(map, truth);
  // Within 10 cm of a square: columns 1–3 (the wall; columns 0 and 4 are 12 cm off) and the
  // table's columns 5–7 in rows 0–1. Occupied: (1,0), (2,1), (6,0) on it; (7,3) is not (the
  // wall above it is above the band).
  EXPECT_EQ(s.occupied_pixels, 4u);
  EXPECT_EQ(s.occupied_on_surface, 3u);
  EXPECT_DOUBLE_EQ(s.precision(), 0.75);
  // Wall pixels: (2, −2..6). Within 10 cm of a square: |dx|, |dy| ≤ 2 but not both 2 (16 cm
  // apart diagonally 11.3 cm). Rows −2..3 reach an occupied pixel ((1,0) or (2,1)); row 4 only
  // free row 2; rows 5 and 6 only unknown pixels.
  EXPECT_EQ(s.obstacle_pixels_known, 7u);
  EXPECT_EQ(s.obstacle_pixels_found, 6u);
  EXPECT_EQ(s.obstacle_pixels_unknown, 2u);
  EXPECT_NEAR(s.wallRecall(), 6.0 / 7.0, 1e-12);

  // The band decides: with the high wall in it, (7,3) is on it and column 7 rows 2–3 are wall
  // pixels too ((7,2) free and known, (7,3) occupied: both found).
  OccupancyScoreOptions all;
  all.max_z_m = 2.5;
  const OccupancyScore tall = scoreOccupancy(map, truth, all);
  EXPECT_EQ(tall.occupied_on_surface, 4u);
  EXPECT_EQ(tall.obstacle_pixels_known, 9u);
  EXPECT_EQ(tall.obstacle_pixels_found, 8u);
}

}  // namespace
}  // namespace stereo_fusion::eval
