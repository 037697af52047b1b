// Prints doc/parameters.md (markdown, the default: the mapping and the node parameters) or the
// default YAML of the mapping parameters (config/default.yaml's keys), from the registries in
// MapperConfig.cpp and ros/RosParameters.cpp, so the documentation cannot drift from the code.
//   stereo_fusion_parameters [--markdown | --yaml]
#include <cstdio>
#include <cstring>

#include "docs/ParameterPage.h"
#include "stereo_fusion/MapperConfig.h"

int main(int argc, char** argv) {
  using namespace stereo_fusion;
  if (argc > 1 && std::strcmp(argv[1], "--yaml") == 0) {
    const MapperConfig defaults;
    for (const ParameterSpec& p : mapperParameterSpecs())
      std::printf("%s: %s\n", p.name.c_str(), getMapperParameter(defaults, p.name).c_str());
    return 0;
  }
  std::fputs(parameterPageMarkdown().c_str(), stdout);
  return 0;
}
