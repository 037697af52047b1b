// Prints doc/parameters.md (markdown, the default: the mapping and the node parameters) or the
// default YAML of the mapping parameters (config/default.yaml's keys), from the registries in
// MapperConfig.cpp and ros/RosParameters.cpp, so the documentation cannot drift from the code.
//   stereo_fusion_parameters [--markdown | --yaml]
#include <cstdio>

#include "cli/CommandLine.h"
#include "docs/ParameterPage.h"
#include "stereo_fusion/MapperConfig.h"

int main(int argc, char** argv) {
  using namespace stereo_fusion;
  CLI::App app(
      "Prints the parameter page doc/parameters.md (the mapping and the node parameters) or the\n"
      "mapping parameters' defaults as YAML (config/default.yaml's keys), from the registries\n"
      "the code validates against.",
      "stereo_fusion_parameters");
  bool yaml = false;
  app.add_flag("--markdown", "print doc/parameters.md (the default)");
  app.add_flag("--yaml", yaml, "print the mapping parameters' defaults as YAML instead");
  if (const auto exit_code = cli::parseOrExitCode(app, argc, argv)) return *exit_code;
  if (yaml) {
    const MapperConfig defaults;
    for (const ParameterSpec& p : mapperParameterSpecs())
      std::printf("%s: %s\n", p.name.c_str(), getMapperParameter(defaults, p.name).c_str());
    return 0;
  }
  std::fputs(parameterPageMarkdown().c_str(), stdout);
  return 0;
}
