#include "stereo_fusion/io/PlanningExport.h"

#include <cstring>
#include <fstream>
#include <sstream>
#include <utility>
#include <vector>

#include "stereo_fusion/io/WriteTarget.h"

namespace stereo_fusion {

bool writeEsdfPly(const std::string& path, const PlanningMap& planning, std::string* error) {
  size_t cells = 0;  // counted first: a vector grown by doubling would hold up to twice the bytes
  planning.forEachKnownCell([&](const CellIndex&, CellState, double) { ++cells; });
  std::vector<std::pair<CellIndex, float>> known;
  known.reserve(cells);
  planning.forEachKnownCell([&](const CellIndex& cell, CellState, double distance_m) {
    known.emplace_back(cell, static_cast<float>(distance_m));
  });
  // centreSdfM() takes the layer's lock: read after the visitor has let go of it.
  std::vector<float> vertices;  // x y z distance centre_sdf
  vertices.reserve(5 * known.size());
  for (const auto& [cell, distance_m] : known) {
    const Eigen::Vector3d p = planning.grid().centre(cell);
    vertices.insert(vertices.end(), {static_cast<float>(p.x()), static_cast<float>(p.y()),
                                     static_cast<float>(p.z()), distance_m,
                                     static_cast<float>(planning.centreSdfM(cell))});
  }
  return writeThroughTemporary(
      path, "ESDF point cloud",
      [&](const std::string& temporary, std::string* e) {
        std::ofstream out(temporary, std::ios::binary);
        out << "ply\nformat binary_little_endian 1.0\ncomment stereo_fusion ESDF, cell "
            << planning.grid().cell_m << " m, max distance " << planning.config().max_distance_m
            << " m\nelement vertex " << vertices.size() / 5
            << "\nproperty float x\nproperty float y\nproperty float z\nproperty float "
               "distance\nproperty float centre_sdf\nend_header\n";
        out.write(reinterpret_cast<const char*>(vertices.data()),
                  static_cast<std::streamsize>(vertices.size() * sizeof(float)));
        if (!out) *e = temporary + ": write failed";
        return static_cast<bool>(out);
      },
      error);
}

bool writeOccupancyMap(const std::string& pgm_path, const std::string& yaml_path,
                       const OccupancyGrid2D& grid, std::string* error) {
  const bool pgm_ok = writeThroughTemporary(
      pgm_path, "occupancy image",
      [&](const std::string& temporary, std::string* e) {
        std::ofstream out(temporary, std::ios::binary);
        out << "P5\n# stereo_fusion occupancy grid\n"
            << grid.width << " " << grid.height << "\n255\n";
        std::vector<uint8_t> row(static_cast<size_t>(grid.width));
        for (int y = grid.height - 1; y >= 0; --y) {  // the image's top row is the largest y
          for (int x = 0; x < grid.width; ++x) {
            const int8_t c = grid.at(x, y);
            row[x] =
                c == OccupancyGrid2D::kOccupied ? 0 : (c == OccupancyGrid2D::kFree ? 254 : 205);
          }
          out.write(reinterpret_cast<const char*>(row.data()),
                    static_cast<std::streamsize>(row.size()));
        }
        if (!out) *e = temporary + ": write failed";
        return static_cast<bool>(out);
      },
      error);
  if (!pgm_ok) return false;
  std::string image = pgm_path;
  const size_t slash = image.find_last_of('/');
  if (slash != std::string::npos) image = image.substr(slash + 1);
  return writeThroughTemporary(
      yaml_path, "occupancy map description",
      [&](const std::string& temporary, std::string* e) {
        std::ofstream out(temporary);
        out.precision(9);
        // map_server reads a cell as occupied above occupied_thresh and free below free_thresh
        // of (255 − value) / 255: 0 → 1 (occupied), 254 → 0.004 (free), 205 → 0.196 (unknown).
        out << "image: " << image << "\nresolution: " << grid.resolution_m << "\norigin: ["
            << grid.origin_x_m << ", " << grid.origin_y_m
            << ", 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
            << "mode: trinary\n";
        if (!out) *e = temporary + ": write failed";
        return static_cast<bool>(out);
      },
      error);
}

}  // namespace stereo_fusion
