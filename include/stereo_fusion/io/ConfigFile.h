#pragma once
#include <string>

#include "stereo_fusion/MapperConfig.h"

namespace stereo_fusion {

/// Reads a flat YAML map of parameters (config/default.yaml's format) on top of `config`.
/// Unknown keys, non-scalar values, unparsable or out-of-range values are errors: the message
/// names the file, the line and the parameter, and `config` is left unchanged.
bool loadMapperConfigFile(const std::string& path, MapperConfig* config, std::string* error);

/// The same from YAML text (`source_name` is used in messages).
bool loadMapperConfigText(const std::string& yaml_text, const std::string& source_name,
                          MapperConfig* config, std::string* error);

}  // namespace stereo_fusion
