#pragma once
// doc/parameters.md, generated from the parameter registries (mapperParameterSpecs(),
// nodeParameterSpecs()), so the reference cannot drift from the code:
// `stereo_fusion_parameters --markdown > doc/parameters.md` writes it, and a test compares the
// file with it.
#include <string>

namespace stereo_fusion {

/// The whole page: how parameters are set, then the mapping parameters and the node parameters,
/// one table row per parameter in registry order (name, unit, default, accepted range, meaning).
std::string parameterPageMarkdown();

}  // namespace stereo_fusion
