#include "stereo_fusion/io/ConfigFile.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>

#include "stereo_fusion/io/TextFile.h"

namespace stereo_fusion {

bool loadMapperConfigText(const std::string& yaml_text, const std::string& source_name,
                          MapperConfig* config, std::string* error, OtherParameters* others) {
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
  std::vector<std::string> known;
  for (const ParameterSpec& spec : mapperParameterSpecs()) known.push_back(spec.name);
  const size_t mapping_names = known.size();
  if (others) known.insert(known.end(), others->names.begin(), others->names.end());
  MapperConfig updated = *config;
  std::vector<std::pair<std::string, std::string>> found;
  for (const auto& entry : root) {
    const std::string key = entry.first.as<std::string>();
    const std::string where = source_name + ":" + std::to_string(entry.first.Mark().line + 1);
    if (!entry.second.IsScalar()) {
      *error = where + ": parameter '" + key + "' must be a single value";
      return false;
    }
    const auto at = std::find(known.begin(), known.end(), key);
    if (at == known.end()) {
      *error = where + ": " + parameter_text::unknownParameterMessage(key, key, known);
      return false;
    }
    if (static_cast<size_t>(at - known.begin()) >= mapping_names) {
      found.emplace_back(key, entry.second.Scalar());
      continue;
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
  if (others) others->found.insert(others->found.end(), found.begin(), found.end());
  return true;
}

bool loadMapperConfigFile(const std::string& path, MapperConfig* config, std::string* error,
                          OtherParameters* others) {
  std::string text;
  if (!readTextFile(path, &text)) {
    *error = path + ": cannot open configuration file";
    return false;
  }
  return loadMapperConfigText(text, path, config, error, others);
}

}  // namespace stereo_fusion
