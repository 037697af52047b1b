// Prints the parameter table of the README (markdown) or the default YAML, from the one
// registry in MapperConfig.cpp, so the documentation cannot drift from the code.
//   stereo_fusion_parameters [--markdown | --yaml]
#include <cstdio>
#include <cstring>
#include <string>

#include "stereo_fusion/MapperConfig.h"

int main(int argc, char** argv) {
  using namespace stereo_fusion;
  const bool yaml = argc > 1 && std::strcmp(argv[1], "--yaml") == 0;
  const MapperConfig defaults;
  if (yaml) {
    for (const ParameterSpec& p : mapperParameterSpecs())
      std::printf("%s: %s\n", p.name.c_str(), getMapperParameter(defaults, p.name).c_str());
    return 0;
  }
  auto cell = [](std::string text) {  // a '|' inside a cell would end it
    for (size_t at = text.find('|'); at != std::string::npos; at = text.find('|', at + 2))
      text.replace(at, 1, "\\|");
    return text;
  };
  std::printf("| parameter | unit | default | range | meaning |\n|---|---|---|---|---|\n");
  for (const ParameterSpec& p : mapperParameterSpecs())
    std::printf("| `%s` | %s | `%s` | %s | %s |\n", p.name.c_str(), p.unit.empty() ? "–" : p.unit.c_str(),
                getMapperParameter(defaults, p.name).c_str(), cell(p.range).c_str(),
                cell(p.description).c_str());
  return 0;
}
