#include "cli/MapperConfigArguments.h"

#include <CLI/CLI.hpp>

#include "stereo_fusion/io/ConfigFile.h"

namespace stereo_fusion::cli {

void addMapperConfigArguments(CLI::App* app, MapperConfigArguments* arguments) {
  app->add_option("--config", arguments->config_file,
                  "parameters in config/default.yaml's format (applied before --set)")
      ->check(CLI::ExistingFile);
  app->add_option("--set", arguments->sets,
                  "override one parameter (repeatable); every key of config/default.yaml is\n"
                  "accepted")
      ->type_name("key=value")
      ->allow_extra_args(false);  // one key=value per --set: the next word may be a path
}

bool applyMapperConfigArguments(const MapperConfigArguments& arguments, MapperConfig* config,
                                std::string* error) {
  if (!arguments.config_file.empty() && !loadMapperConfigFile(arguments.config_file, config, error))
    return false;
  for (const std::string& s : arguments.sets) {
    const size_t eq = s.find('=');
    if (eq == std::string::npos) {
      *error = "--set expects key=value, got '" + s + "'";
      return false;
    }
    if (!setMapperParameter(config, s.substr(0, eq), s.substr(eq + 1), error)) return false;
  }
  const auto problems = validateMapperConfig(*config);
  if (!problems.empty()) {
    *error = problems.front();
    return false;
  }
  return true;
}

}  // namespace stereo_fusion::cli
