#pragma once
#include <string>
#include <utility>
#include <vector>

#include "stereo_fusion/MapperConfig.h"

namespace stereo_fusion {

/// Keys a configuration file may hold beside the mapping parameters — the nodelet's own, so that
/// one file serves the node and the offline fuser: accepted but not applied to the MapperConfig,
/// handed back with their values for the caller to check and use or ignore.
struct OtherParameters {
  std::vector<std::string> names;                          ///< the names accepted
  std::vector<std::pair<std::string, std::string>> found;  ///< (name, value), in file order
};

/// Reads a flat YAML map of parameters (config/default.yaml's format) on top of `config`.
/// Unknown keys (named with the nearest known name), non-scalar values, unparsable or
/// out-of-range values are errors: the message names the file, the line and the parameter, and
/// `config` is left unchanged. With `others`, its names are known too and land in others->found.
bool loadMapperConfigFile(const std::string& path, MapperConfig* config, std::string* error,
                          OtherParameters* others = nullptr);

/// The same from YAML text (`source_name` is used in messages).
bool loadMapperConfigText(const std::string& yaml_text, const std::string& source_name,
                          MapperConfig* config, std::string* error,
                          OtherParameters* others = nullptr);

}  // namespace stereo_fusion
