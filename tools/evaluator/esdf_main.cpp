// stereo_fusion_evaluate_esdf OUT/esdf.ply [SEQ | gt_mesh.ply] [--max-distance-m D]
//                             [--grid-band ZMIN,ZMAX] [--before EARLIER/esdf.ply] [--json FILE]
// (--help describes each).
//
// How exact an ESDF is: every free cell's distance against (1) the brute force — the distance
// from its centre to the nearest occupied cell centre of the same file, by an exact k-d tree
// search (PCL) — and (2) with a ground-truth mesh, the distance from its centre to the true
// surface (exact point-to-triangle distances). Both by band of the reference distance.
// (3) With a ground-truth mesh also the planning report: the truth read as solids
// (evaluator/SolidTruth), scored as a planner meets it (evaluator/PlanningScore), and the
// folder's occupancy.pgm against the true surface of its height band (evaluator/OccupancyScore).
// With --before, the free cells an earlier run of the same frames also calls free, both
// scored against the truth: how many read worse by more than half a cell (evaluator/EsdfDelta).
#include <pcl/PCLPointCloud2.h>
#include <pcl/io/ply_io.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "cli/CommandLine.h"
#include "cli/NumberChecks.h"
#include "evaluator/EsdfAccuracy.h"
#include "evaluator/EsdfDelta.h"
#include "evaluator/OccupancyMapFile.h"
#include "evaluator/OccupancyScore.h"
#include "evaluator/PlanningScore.h"
#include "evaluator/SolidTruth.h"
#include "evaluator/TriangleBvh.h"
#include "readers/PlyReader.h"

namespace fs = std::filesystem;
using namespace stereo_fusion;

namespace {

/// The command line.
struct EsdfArguments {
  std::string esdf_path;        ///< OUT/esdf.ply
  std::string reference;        ///< a sequence folder (its gt_mesh.ply) or a mesh; empty: none
  double max_distance_m = 0.0;  ///< 0: the largest |distance| in the file
  std::pair<double, double> grid_band_m{0.0, 0.0};
  bool grid_band_given = false;
  std::string before_path;  ///< an earlier run's esdf.ply; empty: none
  std::string json_path;    ///< empty: no JSON file
};

void addEsdfArguments(CLI::App* app, EsdfArguments* args) {
  app->description(
      "How exact an ESDF is: every free cell's distance against the brute force (the nearest\n"
      "occupied cell of the same file, PCL's exact k-d tree) and, with a ground-truth mesh,\n"
      "against the true surface, by band of the reference distance; with a ground truth also\n"
      "the planning report (solid truth, occupancy.pgm beside esdf.ply) and, with --before,\n"
      "the free cells that read worse than in an earlier run of the same frames.");
  app->footer("Exit codes: 0 done, 1 unreadable input, 2 bad arguments.");
  app->add_option("esdf", args->esdf_path, "the fuser's OUT/esdf.ply")->required();
  app->add_option("reference", args->reference,
                  "SEQ-FOLDER (its gt_mesh.ply) or gt_mesh.ply: the ground truth (optional)");
  app->add_option("--max-distance-m", args->max_distance_m,
                  "the ESDF's cap in metres (the run's esdf_max_distance_m): the last band ends\n"
                  "there and reference distances are clamped to it (default: the largest\n"
                  "|distance| in the file)")
      ->check(cli::positiveNumber());
  CLI::Option* band =
      app->add_option("--grid-band", args->grid_band_m,
                      "the occupancy grid's height band in metres, ZMIN < ZMAX (default: the\n"
                      "run's stats.json, else 0.1,1.5)")
          ->delimiter(',')
          ->type_name("ZMIN,ZMAX");
  app->add_option("--before", args->before_path,
                  "an earlier run's esdf.ply of the same frames: the free cells both call free,\n"
                  "scored against the truth, and those that read worse by over half a cell")
      ->type_name("EARLIER/esdf.ply");
  app->add_option("--json", args->json_path, "also write the results as JSON")->type_name("FILE");
  app->callback([args, band] {
    args->grid_band_given = band->count() > 0;
    if (args->grid_band_given && !(args->grid_band_m.first < args->grid_band_m.second))
      throw CLI::ValidationError("--grid-band", "expected ZMIN,ZMAX with ZMIN < ZMAX");
  });
}

/// The cells of an esdf.ply (x y z distance, as io/PlanningExport writes it), via PCL's reader.
bool readEsdf(const std::string& path, EsdfCells* cells, double* max_distance_m,
              std::string* error) {
  pcl::PCLPointCloud2 cloud;
  if (pcl::io::loadPLYFile(path, cloud) < 0) {
    *error = path + ": not a readable PLY point cloud";
    return false;
  }
  int offsets[4] = {-1, -1, -1, -1};
  const char* names[4] = {"x", "y", "z", "distance"};
  for (const pcl::PCLPointField& f : cloud.fields)
    for (int i = 0; i < 4; ++i)
      if (f.name == names[i] && f.datatype == pcl::PCLPointField::FLOAT32)
        offsets[i] = static_cast<int>(f.offset);
  for (int i = 0; i < 4; ++i)
    if (offsets[i] < 0) {
      *error = path + ": no float property '" + names[i] + "' (not an esdf.ply?)";
      return false;
    }
  int centre_sdf_offset = -1;  // optional: files written before sub-cell distances lack it
  for (const pcl::PCLPointField& f : cloud.fields)
    if (f.name == "centre_sdf" && f.datatype == pcl::PCLPointField::FLOAT32)
      centre_sdf_offset = static_cast<int>(f.offset);
  const size_t n = static_cast<size_t>(cloud.width) * cloud.height;
  double largest = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const uint8_t* point = cloud.data.data() + i * cloud.point_step;
    float v[4];
    for (int k = 0; k < 4; ++k) std::memcpy(&v[k], point + offsets[k], sizeof(float));
    const Eigen::Vector3d p(v[0], v[1], v[2]);
    if (v[3] < 0.0f) {
      cells->occupied_centres.push_back(p);
      float centre_sdf = 0.0f;
      if (centre_sdf_offset >= 0)
        std::memcpy(&centre_sdf, point + centre_sdf_offset, sizeof(float));
      cells->occupied_centre_sdf_m.push_back(centre_sdf);
    } else {
      cells->free_centres.push_back(p);
      cells->free_distances_m.push_back(v[3]);
    }
    largest = std::max(largest, std::abs(static_cast<double>(v[3])));
  }
  if (*max_distance_m <= 0.0) *max_distance_m = largest;
  return true;
}

nlohmann::ordered_json toJson(const EsdfAccuracy& a) {
  nlohmann::ordered_json bands = nlohmann::ordered_json::array();
  for (const EsdfBand& b : a.bands)
    bands.push_back({{"lo_m", b.lo_m},
                     {"hi_m", b.hi_m},
                     {"cells", b.cells},
                     {"median_m", b.median_m},
                     {"p99_m", b.p99_m},
                     {"max_m", b.max_m},
                     {"mean_signed_m", b.mean_signed_m},
                     {"over_tolerance", b.over_tolerance},
                     {"tolerance_m", a.tolerance_m}});
  return bands;
}

nlohmann::ordered_json toJson(const PlanningScore& s) {
  const PlanningScoreOptions& o = s.options;
  nlohmann::ordered_json j;
  j["truth"] = "solid: negative behind the nearest triangle's winding normal";
  j["free_near_surface"] = {{"lo_m", o.near_lo_m},
                            {"hi_m", std::min(o.near_hi_m, s.max_distance_m)},
                            {"cells", s.near_cells},
                            {"median_m", s.near_median_m},
                            {"p90_m", s.near_p90_m},
                            {"nearest_seen_cells", s.near_seen_cells},
                            {"nearest_seen_median_m", s.near_seen_median_m},
                            {"nearest_seen_p90_m", s.near_seen_p90_m},
                            {"too_close_m", o.too_close_m},
                            {"too_close_cells", s.near_too_close},
                            {"too_close_share", shareOf(s.near_too_close, s.near_cells)}};
  j["phantom_occupied"] = {{"min_distance_m", o.phantom_m},
                           {"cells", s.phantom_cells},
                           {"occupied_cells", s.occupied_cells},
                           {"share", shareOf(s.phantom_cells, s.occupied_cells)},
                           {"median_distance_m", s.phantom_median_distance_m},
                           {"median_z_m", s.phantom_median_z_m},
                           {"centres", nlohmann::ordered_json::array()}};
  for (const Eigen::Vector3d& c : s.phantom_centres)
    j["phantom_occupied"]["centres"].push_back({c.x(), c.y(), c.z()});
  j["free_inside_solid"] = {{"min_esdf_m", o.clear_min_m},
                            {"cells", s.clear_cells},
                            {"inside_cells", s.clear_inside_solid},
                            {"share", shareOf(s.clear_inside_solid, s.clear_cells)}};
  return j;
}

nlohmann::ordered_json toJson(const eval::OccupancyScore& s, const std::string& yaml,
                              const std::string& band_from) {
  return {{"map", yaml},
          {"band_m", {s.options.min_z_m, s.options.max_z_m}},
          {"band_from", band_from},
          {"reach_m", s.options.reach_m},
          {"precision", s.precision()},
          {"occupied_pixels", s.occupied_pixels},
          {"occupied_on_surface", s.occupied_on_surface},
          {"wall_recall", s.wallRecall()},
          {"wall_pixels_known", s.obstacle_pixels_known},
          {"wall_pixels_found", s.obstacle_pixels_found},
          {"wall_pixels_unseen", s.obstacle_pixels_unknown},
          {"false_pixels", s.false_pixels}};
}

/// The occupancy grid's height band: --grid-band, else the run's own (the config in the
/// stats.json beside esdf.ply, as the fuser writes it), else the mapper's defaults (0.1, 1.5 m,
/// already in `min_z_m`, `max_z_m`). Sets `source`.
void gridBand(const EsdfArguments& args, const fs::path& run_dir, double* min_z_m, double* max_z_m,
              std::string* source) {
  if (args.grid_band_given) {
    *source = "--grid-band";
    *min_z_m = args.grid_band_m.first, *max_z_m = args.grid_band_m.second;
    return;
  }
  *source = "defaults";
  std::ifstream stats(run_dir / "stats.json");
  if (!stats) return;
  const nlohmann::json j = nlohmann::json::parse(stats, nullptr, false);
  if (j.is_discarded() || !j.contains("config") || !j["config"].is_object()) return;
  // The fuser writes every parameter as text (getMapperParameter).
  const auto number = [&](const char* key, double* value) {
    const nlohmann::json v = j["config"].value(key, nlohmann::json());
    if (v.is_number()) *value = v.get<double>();
    if (!v.is_string()) return v.is_number();
    std::istringstream in(v.get<std::string>());
    return static_cast<bool>(in >> *value);
  };
  double lo = 0.0, hi = 0.0;
  if (number("grid_min_z_m", &lo) && number("grid_max_z_m", &hi) && lo < hi) {
    *min_z_m = lo, *max_z_m = hi;
    *source = "stats.json";
  }
}

/// The evaluation (see the top of the file); returns the exit code.
int evaluateEsdf(const EsdfArguments& args) {
  const std::string& esdf_path = args.esdf_path;
  const std::string& reference = args.reference;
  double max_distance_m = args.max_distance_m;  // 0 until the file's largest is read
  const fs::path run_dir = fs::path(esdf_path).parent_path();
  eval::OccupancyScoreOptions grid_options;
  std::string band_from;
  gridBand(args, run_dir, &grid_options.min_z_m, &grid_options.max_z_m, &band_from);
  EsdfCells cells;
  std::string error;
  if (!readEsdf(esdf_path, &cells, &max_distance_m, &error)) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return 1;
  }
  std::printf("%zu free and %zu occupied cells, max distance %.3f m\n", cells.free_centres.size(),
              cells.occupied_centres.size(), max_distance_m);
  const std::vector<double> edges = {0.25, 0.5, 1.0, max_distance_m + 1e-9};
  nlohmann::ordered_json json;

  // (1) Brute force over the file's own occupied cells.
  pcl::PointCloud<pcl::PointXYZ>::Ptr occupied(new pcl::PointCloud<pcl::PointXYZ>);
  for (const Eigen::Vector3d& p : cells.occupied_centres)
    occupied->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  double cell_m = INFINITY;              // the grid's spacing: the nearest other occupied centre
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;  // a single k-d tree searched exactly
  if (!occupied->empty()) {
    tree.setInputCloud(occupied);
    std::vector<int> index(2);
    std::vector<float> squared(2);
    for (size_t i = 0; i < occupied->size(); i += std::max<size_t>(1, occupied->size() / 200))
      if (tree.nearestKSearch((*occupied)[i], 2, index, squared) == 2)
        cell_m = std::min(cell_m, std::sqrt(double(squared[1])));
    std::printf("cell edge %.4f m (the nearest two occupied centres)\n", cell_m);
    const EsdfAccuracy brute = compareEsdf(
        cells, max_distance_m, edges,
        [&](const Eigen::Vector3d& p) {
          // Float centres: the cells' own distances are exact in double; search in float, then
          // measure in double.
          if (tree.nearestKSearch(pcl::PointXYZ(p.x(), p.y(), p.z()), 1, index, squared) < 1)
            return double(INFINITY);
          // Moved onto the site's surface as the ESDF reads it (sub-cell distances).
          const double centres_m = (cells.occupied_centres[index[0]] - p).norm();
          return std::clamp(centres_m - cells.occupied_centre_sdf_m[index[0]], 0.0, max_distance_m);
        },
        0.5 * cell_m);
    std::printf(
        "%s",
        brute.describe("against the brute force (nearest occupied cell, its centre_sdf applied):")
            .c_str());
    json["brute_force"] = toJson(brute);
  }
  // (2) Ground truth.
  if (!reference.empty()) {
    const std::string mesh_path =
        fs::is_directory(reference) ? (fs::path(reference) / "gt_mesh.ply").string() : reference;
    TriangleMesh mesh;
    if (!readPly(mesh_path, &mesh, &error)) {
      std::fprintf(stderr, "%s\n", error.c_str());
      return 1;
    }
    const eval::SolidTruth solid(mesh);
    const eval::TriangleBvh& bvh = solid.bvh();
    const double diagonal = std::isfinite(cell_m) ? 0.5 * std::sqrt(3.0) * cell_m : 0.0;
    const EsdfAccuracy truth = compareEsdf(
        cells, max_distance_m, edges, [&](const Eigen::Vector3d& p) { return bvh.distance(p); },
        diagonal);
    std::printf(
        "%s", truth.describe("against the true surface (" + mesh_path + "), seen or not:").c_str());
    json["ground_truth"] = toJson(truth);
    // The same where the nearest true surface point lies in an occupied cell (within half a
    // cell diagonal of its centre): what the ESDF's grid costs where the map saw the surface.
    // The distance to that point, or infinity where the map did not see it.
    std::vector<int> index(1);
    std::vector<float> squared(1);
    const double reach = diagonal + 1e-6;
    const auto seen_distance = [&](const Eigen::Vector3d& p) {
      eval::NearestSurfacePoint nearest;
      if (occupied->empty() || !bvh.nearest(p, &nearest)) return double(INFINITY);
      const Eigen::Vector3d& q = nearest.point_m;
      if (tree.nearestKSearch(pcl::PointXYZ(q.x(), q.y(), q.z()), 1, index, squared) < 1)
        return double(INFINITY);
      if ((cells.occupied_centres[index[0]] - q).norm() > reach) return double(INFINITY);
      return nearest.distance_m;
    };
    if (!occupied->empty()) {
      const EsdfAccuracy seen = compareEsdf(cells, max_distance_m, edges, seen_distance, diagonal);
      std::printf(
          "%s",
          seen.describe("against the true surface where its nearest point was seen (occupied):")
              .c_str());
      json["ground_truth_seen"] = toJson(seen);
    }
    // (2b) Against an earlier run of the same frames: the free cells both call free, each
    // scored against the truth, and those that read worse than before by over half a cell.
    const std::string& before_path = args.before_path;
    if (!before_path.empty() && std::isfinite(cell_m)) {
      EsdfCells before;
      double before_max_m = 0.0;
      if (!readEsdf(before_path, &before, &before_max_m, &error)) {
        std::fprintf(stderr, "%s\n", error.c_str());
        return 1;
      }
      const eval::CellDelta delta = eval::compareWithBefore(
          cells, before, max_distance_m, cell_m,
          [&](const Eigen::Vector3d& p) { return solid.signedDistance(p); });
      std::printf("%s", delta.describe(before_path).c_str());
      json["before"] = eval::toJson(delta, before_path);
    }
    // (3) The planning report.
    if (!bvh.empty()) {
      const PlanningScore planning = scorePlanning(
          cells, max_distance_m, [&](const Eigen::Vector3d& p) { return solid.signedDistance(p); },
          PlanningScoreOptions{},
          [&](const Eigen::Vector3d& p) { return std::isfinite(seen_distance(p)); });
      std::printf("%s", planning.describe().c_str());
      json["planning"] = toJson(planning);
      const fs::path yaml = run_dir / "occupancy.yaml";
      if (fs::exists(yaml)) {
        eval::OccupancyMap map;
        if (!eval::readOccupancyMap(yaml.string(), &map, &error)) {
          std::fprintf(stderr, "%s\n", error.c_str());
          return 1;
        }
        const eval::OccupancyScore grid = eval::scoreOccupancy(map, mesh, grid_options, &solid);
        std::printf("%s", grid.describe("occupancy.pgm", band_from).c_str());
        json["planning"]["occupancy"] = toJson(grid, yaml.string(), band_from);
      }
    }
  }
  if (!args.json_path.empty()) std::ofstream(args.json_path) << json.dump(2) << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  EsdfArguments args;
  CLI::App app("", "stereo_fusion_evaluate_esdf");
  addEsdfArguments(&app, &args);
  if (const auto exit_code = cli::parseOrExitCode(app, argc, argv)) return *exit_code;
  return evaluateEsdf(args);
}
