#include "stereo_fusion/io/ConfigFile.h"

#include <yaml-cpp/yaml.h>

#include "stereo_fusion/io/TextFile.h"

namespace stereo_fusion {

bool loadMapperConfigText(const std::string& yaml_text, const std::string& source_name,
                          MapperConfig* config, std::string* error) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    *error = source_name + ": not valid YAML: " + e.what();
    return false;
  }
  if (root.IsNull()) return true;  // an empty file changes nothing
  if (!root.IsMap()) {
    *error = source_name + ": expected a map of 'parameter: value' lines";
    return false;
  }
  MapperConfig updated = *config;
  for (const auto& entry : root) {
    const std::string key = entry.first.as<std::string>();
    const std::string where = source_name + ":" + std::to_string(entry.first.Mark().line + 1);
    if (!entry.second.IsScalar()) {
      *error = where + ": parameter '" + key + "' must be a single value";
      return false;
    }
    std::string why;
    if (!setMapperParameter(&updated, key, entry.second.Scalar(), &why)) {
      *error = where + ": " + why;
      return false;
    }
  }
  for (const std::string& e : validateMapperConfig(updated)) {
    *error = source_name + ": " + e;
    return false;
  }
  *config = updated;
  return true;
}

bool loadMapperConfigFile(const std::string& path, MapperConfig* config, std::string* error) {
  std::string text;
  if (!readTextFile(path, &text)) {
    *error = path + ": cannot open configuration file";
    return false;
  }
  return loadMapperConfigText(text, path, config, error);
}

}  // namespace stereo_fusion
