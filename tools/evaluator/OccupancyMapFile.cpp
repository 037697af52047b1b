#include "evaluator/OccupancyMapFile.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

namespace stereo_fusion::eval {

bool readOccupancyMap(const std::string& yaml_path, OccupancyMap* map, std::string* error) {
  YAML::Node root;
  std::string image, mode = "trinary";
  double occupied_thresh = 0.0, free_thresh = 0.0, yaw = 0.0;
  bool negate = false;
  try {
    root = YAML::LoadFile(yaml_path);
    for (const char* key : {"image", "resolution", "origin", "occupied_thresh", "free_thresh"})
      if (!root[key]) {
        *error = yaml_path + ": no '" + key + "' (not a map_server map?)";
        return false;
      }
    image = root["image"].as<std::string>();
    map->resolution_m = root["resolution"].as<double>();
    const YAML::Node origin = root["origin"];
    if (!origin.IsSequence() || origin.size() != 3) {
      *error = yaml_path + ": origin must be [x, y, yaw]";
      return false;
    }
    map->origin_x_m = origin[0].as<double>();
    map->origin_y_m = origin[1].as<double>();
    yaw = origin[2].as<double>();
    occupied_thresh = root["occupied_thresh"].as<double>();
    free_thresh = root["free_thresh"].as<double>();
    if (root["negate"]) negate = root["negate"].as<int>() != 0;
    if (root["mode"]) mode = root["mode"].as<std::string>();
  } catch (const YAML::Exception& e) {
    *error = yaml_path + ": " + e.what();
    return false;
  }
  if (!(map->resolution_m > 0.0) || yaw != 0.0 || (mode != "trinary" && mode != "scale")) {
    *error = yaml_path + ": needs resolution > 0, origin yaw 0 and mode trinary or scale";
    return false;
  }
  // map_server resolves a relative image against the YAML's folder.
  std::filesystem::path image_path(image);
  if (image_path.is_relative())
    image_path = std::filesystem::path(yaml_path).parent_path() / image_path;
  const cv::Mat pixels = cv::imread(image_path.string(), cv::IMREAD_UNCHANGED);
  if (pixels.empty() || pixels.depth() != CV_8U) {
    *error = image_path.string() + ": not a readable 8-bit image";
    return false;
  }
  map->width = pixels.cols;
  map->height = pixels.rows;
  map->cells.assign(static_cast<size_t>(map->width) * map->height, OccupancyMap::kUnknown);
  // map_server averages every channel in trinary mode, and leaves an alpha channel (the fourth,
  // or the second of two) out in scale mode.
  const int channels = pixels.channels();
  const bool alpha = channels == 2 || channels == 4;
  const int colour = alpha && mode == "scale" ? channels - 1 : channels;
  for (int row = 0; row < pixels.rows; ++row) {
    const uint8_t* p = pixels.ptr<uint8_t>(row);
    for (int x = 0; x < pixels.cols; ++x, p += channels) {
      double value = 0.0;
      for (int k = 0; k < colour; ++k) value += p[k];
      value /= colour;
      if (negate) value = 255.0 - value;
      const double occupancy = (255.0 - value) / 255.0;
      int8_t cell = OccupancyMap::kUnknown;
      if (occupancy > occupied_thresh)
        cell = OccupancyMap::kOccupied;
      else if (occupancy < free_thresh)
        cell = OccupancyMap::kFree;
      else if (mode == "scale")
        cell = static_cast<int8_t>(1 + 98 * (occupancy - free_thresh) /
                                           (occupied_thresh - free_thresh));
      map->cells[static_cast<size_t>(map->height - 1 - row) * map->width + x] = cell;
    }
  }
  return true;
}

}  // namespace stereo_fusion::eval
