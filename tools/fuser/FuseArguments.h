#pragma once
// The fuser's command line: its arguments on a CLI11 app (stereo_fusion_fuse, and
// stereo_fusion_texture_compare, which fuses the same way) and a parse of argument strings.

#include <string>
#include <vector>

#include "cli/MapperConfigArguments.h"
#include "fuser/OfflineFuser.h"

namespace CLI {
class App;
}

namespace stereo_fusion {

/// Adds `fuse <input> <out-dir> [--config FILE] [--set key=value ...] [--frames N] [--mesh-every
/// N] [--esdf-every N] [--time-planning] [--quiet] [--disparity-topic T] [--image-topic T]
/// [--camera-info-topic T] [--world-frame F] [--load-map FILE] [--save-map FILE]
/// [--trajectory FILE] [--frame-log FILE]` to `app`, parsed into `options` (which must outlive
/// the parse); with --load-map the input may be left out (`fuse <out-dir> --load-map FILE`
/// meshes a saved map). After the parse the paths are checked and the parameters applied
/// (applyFuseParameters()); an unknown key, an out-of-range value or a wrong number of paths ends
/// the parse with a CLI::ValidationError naming the parameter or flag.
void addFuseArguments(CLI::App* app, FuseOptions* options);

/// Applies --config, then every --set, whatever their order, to options->config. The nodelet's
/// own keys are accepted beside the mapping parameters (one YAML serves both): each is checked
/// as the node checks it; world_frame becomes the bag's frame unless `world_frame_given`; the
/// others are listed in options->notes. An unknown key's message names the nearest known one of
/// either. False with a message naming the file, parameter or flag.
bool applyFuseParameters(const cli::MapperConfigArguments& parameters, bool world_frame_given,
                         FuseOptions* options, std::string* error);

/// Parses `args` (argv[1..]) as stereo_fusion_fuse does. False with a message (which names the
/// parameter or flag) on any error: unknown flags, unknown keys, out-of-range values.
bool parseFuseArguments(const std::vector<std::string>& args, FuseOptions* options,
                        std::string* error);

}  // namespace stereo_fusion
