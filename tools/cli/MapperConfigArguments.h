#pragma once
// The mapping parameters on a tool's command line: --config FILE and --set key=value (the
// fuser, the texture comparison, the soak).

#include <string>
#include <vector>

#include "stereo_fusion/MapperConfig.h"

namespace CLI {
class App;
}

namespace stereo_fusion::cli {

/// --config and --set as given, applied by applyMapperConfigArguments().
struct MapperConfigArguments {
  std::string config_file;        ///< empty: none
  std::vector<std::string> sets;  ///< "key=value", in order
};

/// Adds --config FILE and --set key=value (repeatable) to `app`, parsed into `arguments`.
void addMapperConfigArguments(CLI::App* app, MapperConfigArguments* arguments);

/// Applies --config, then every --set in order, whatever their order on the command line, and
/// validates the result. False with a message naming the file, parameter or flag.
bool applyMapperConfigArguments(const MapperConfigArguments& arguments, MapperConfig* config,
                                std::string* error);

}  // namespace stereo_fusion::cli
