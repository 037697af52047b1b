// stereo_fusion_evaluate_esdf OUT/esdf.ply [SEQ | gt_mesh.ply] [--max-distance-m D] [--json FILE]
//
// How exact an ESDF is: every free cell's distance against (1) the brute force — the distance
// from its centre to the nearest occupied cell centre of the same file, by an exact k-d tree
// search (PCL) — and (2) with a ground-truth mesh, the distance from its centre to the true
// surface (exact point-to-triangle distances). Both by band of the reference distance.
#include <pcl/PCLPointCloud2.h>
#include <pcl/io/ply_io.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "evaluator/EsdfAccuracy.h"
#include "evaluator/TriangleBvh.h"
#include "readers/PlyReader.h"

namespace fs = std::filesystem;
using namespace stereo_fusion;

namespace {

int usage(const char* why) {
  std::fprintf(stderr,
               "%s\nusage: stereo_fusion_evaluate_esdf OUT/esdf.ply [SEQ-FOLDER | gt_mesh.ply] "
               "[--max-distance-m D (default: the file's)] [--json FILE]\n",
               why);
  return 2;
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
  const size_t n = static_cast<size_t>(cloud.width) * cloud.height;
  double largest = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const uint8_t* point = cloud.data.data() + i * cloud.point_step;
    float v[4];
    for (int k = 0; k < 4; ++k) std::memcpy(&v[k], point + offsets[k], sizeof(float));
    const Eigen::Vector3d p(v[0], v[1], v[2]);
    if (v[3] < 0.0f)
      cells->occupied_centres.push_back(p);
    else {
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

}  // namespace

int main(int argc, char** argv) {
  std::string esdf_path, reference, json_path;
  double max_distance_m = 0.0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--max-distance-m" && i + 1 < argc) {
      max_distance_m = std::atof(argv[++i]);
    } else if (a == "--json" && i + 1 < argc) {
      json_path = argv[++i];
    } else if (a == "-h" || a == "--help") {
      return usage("");
    } else if (esdf_path.empty()) {
      esdf_path = a;
    } else if (reference.empty()) {
      reference = a;
    } else {
      return usage(("unexpected argument " + a).c_str());
    }
  }
  if (esdf_path.empty()) return usage("no esdf.ply given");
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
          return std::min((cells.occupied_centres[index[0]] - p).norm(), max_distance_m);
        },
        0.5 * cell_m);
    std::printf("%s",
                brute.describe("against the brute force (nearest occupied cell centre):").c_str());
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
    const eval::TriangleBvh bvh(mesh);
    const double diagonal = std::isfinite(cell_m) ? 0.5 * std::sqrt(3.0) * cell_m : 0.0;
    const EsdfAccuracy truth = compareEsdf(
        cells, max_distance_m, edges, [&](const Eigen::Vector3d& p) { return bvh.distance(p); },
        diagonal);
    std::printf(
        "%s", truth.describe("against the true surface (" + mesh_path + "), seen or not:").c_str());
    json["ground_truth"] = toJson(truth);
    // The same where the nearest true surface point lies in an occupied cell (within half a
    // cell diagonal of its centre): what the ESDF's grid costs where the map saw the surface.
    if (!occupied->empty()) {
      std::vector<int> index(1);
      std::vector<float> squared(1);
      const double reach = diagonal + 1e-6;
      const EsdfAccuracy seen = compareEsdf(
          cells, max_distance_m, edges,
          [&](const Eigen::Vector3d& p) {
            eval::NearestSurfacePoint nearest;
            if (!bvh.nearest(p, &nearest)) return double(INFINITY);
            const Eigen::Vector3d& q = nearest.point_m;
            if (tree.nearestKSearch(pcl::PointXYZ(q.x(), q.y(), q.z()), 1, index, squared) < 1)
              return double(INFINITY);
            if ((cells.occupied_centres[index[0]] - q).norm() > reach) return double(INFINITY);
            return nearest.distance_m;
          },
          diagonal);
      std::printf(
          "%s",
          seen.describe("against the true surface where its nearest point was seen (occupied):")
              .c_str());
      json["ground_truth_seen"] = toJson(seen);
    }
  }
  if (!json_path.empty()) std::ofstream(json_path) << json.dump(2) << "\n";
  return 0;
}
