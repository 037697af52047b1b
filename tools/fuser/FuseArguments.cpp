// The fuser's command line on CLI11: paths, flags, the parameters (--config, --set), which may
// hold the nodelet's own keys beside the mapping parameters (one YAML for both).
#include "fuser/FuseArguments.h"

#include <algorithm>
#include <memory>

#include "cli/CommandLine.h"
#include "cli/NumberChecks.h"
#include "stereo_fusion/io/ConfigFile.h"
#include "stereo_fusion/ros/RosParameters.h"

namespace stereo_fusion {
namespace {

std::vector<std::string> nodeParameterNames() {
  std::vector<std::string> names;
  for (const ParameterSpec& spec : nodeParameterSpecs()) names.push_back(spec.name);
  return names;
}

/// The nodelet's own parameters given to the fuser (one YAML serves both): each value is checked
/// as the node would check it; world_frame is the frame of a bag's poses unless --world-frame
/// named one; the others mean nothing offline and are listed in a note.
bool applyNodeParameters(const std::vector<std::pair<std::string, std::string>>& found,
                         const std::string& source, bool world_frame_given, FuseOptions* options,
                         std::string* error) {
  NodeConfig checked;
  std::vector<std::string> ignored;
  for (const auto& [name, value] : found) {
    if (!setNodeParameter(&checked, name, value, error)) {
      *error = source + ": " + *error;
      return false;
    }
    if (name == "world_frame") {
      if (!world_frame_given) options->bag_topics.world_frame = value;
    } else if (std::find(ignored.begin(), ignored.end(), name) == ignored.end()) {
      ignored.push_back(name);
    }
  }
  if (ignored.empty()) return true;
  std::string list;
  for (const std::string& name : ignored) list += (list.empty() ? "" : ", ") + name;
  options->notes.push_back(source + ": node parameters, ignored offline: " + list);
  return true;
}

/// What the command line gives besides FuseOptions' own fields: the paths (what they are depends
/// on --load-map) and the parameters' sources.
struct FuseSources {
  std::vector<std::string> paths;
  cli::MapperConfigArguments parameters;
};

/// `sources` into `options`: false with a message on an error.
bool applySources(const FuseSources& sources, bool world_frame_given, FuseOptions* options,
                  std::string* error) {
  const std::vector<std::string>& paths = sources.paths;
  if (paths.size() == 1 && !options->load_map.empty()) {
    options->out_dir = paths[0];  // mesh a saved map, no frames
  } else if (paths.size() == 2) {
    options->input = paths[0];
    options->out_dir = paths[1];
  } else {
    *error = "expected <seq-folder | file.bag> <out-dir> (or <out-dir> with --load-map), got " +
             std::to_string(paths.size()) + " arguments";
    return false;
  }
  if (!options->trajectory.empty() && options->input.empty()) {
    *error = "--trajectory needs the frames it corrects (an input folder or bag)";
    return false;
  }
  return applyFuseParameters(sources.parameters, world_frame_given, options, error);
}

}  // namespace

bool applyFuseParameters(const cli::MapperConfigArguments& parameters, bool world_frame_given,
                         FuseOptions* options, std::string* error) {
  // The nodelet's own keys are accepted beside the mapping parameters (one YAML for both).
  const std::vector<std::string> node_names = nodeParameterNames();
  const std::string& config_file = parameters.config_file;
  if (!config_file.empty()) {
    OtherParameters node_keys{node_names, {}};
    if (!loadMapperConfigFile(config_file, &options->config, error, &node_keys) ||
        !applyNodeParameters(node_keys.found, config_file, world_frame_given, options, error))
      return false;
  }
  std::vector<std::pair<std::string, std::string>> node_sets;
  for (const std::string& s : parameters.sets) {
    const size_t eq = s.find('=');
    if (eq == std::string::npos) {
      *error = "--set expects key=value, got '" + s + "'";
      return false;
    }
    const std::string key = s.substr(0, eq);
    std::vector<std::string> known;
    for (const ParameterSpec& spec : mapperParameterSpecs()) known.push_back(spec.name);
    if (std::find(node_names.begin(), node_names.end(), key) != node_names.end()) {
      node_sets.emplace_back(key, s.substr(eq + 1));
      continue;
    }
    if (std::find(known.begin(), known.end(), key) == known.end()) {
      known.insert(known.end(), node_names.begin(), node_names.end());
      *error = parameter_text::unknownParameterMessage(key, key, known);
      return false;
    }
    if (!setMapperParameter(&options->config, key, s.substr(eq + 1), error)) return false;
  }
  if (!applyNodeParameters(node_sets, "--set", world_frame_given, options, error)) return false;
  const auto problems = validateMapperConfig(options->config);
  if (!problems.empty()) {
    *error = problems.front();
    return false;
  }
  return true;
}

void addFuseArguments(CLI::App* app, FuseOptions* options) {
  // Kept alive by the callback, which the app keeps.
  const auto sources = std::make_shared<FuseSources>();
  app->add_option("paths", sources->paths,
                  "<seq-folder | file.bag> <out-dir>, or <out-dir> alone with --load-map");
  cli::addMapperConfigArguments(app, &sources->parameters);
  app->get_option("--config")
      ->description(
          "parameters in config/default.yaml's format (applied before --set); the nodelet's\n"
          "own keys are accepted too (one file for both): world_frame is a bag's frame (unless\n"
          "--world-frame), the others are checked and ignored");
  app->add_option("--frames", options->max_frames, "fuse only the first N frames (default: all)")
      ->check(cli::nonNegativeNumber());
  app->add_option("--frame-log", options->frame_log,
                  "append '<frame> <unix time s>' after every fused frame (flushed)")
      ->type_name("FILE");
  app->add_option("--mesh-every", options->mesh_every,
                  "bring the mesh up to date after every N-th frame (default 1) and the last\n"
                  "(texture patches are then cut from the frames that end a meshing pass)")
      ->check(cli::positiveNumber());
  app->add_option("--esdf-every", options->esdf_every,
                  "bring the planning layer (occupancy, ESDF) up to date after every N-th frame\n"
                  "(default 10) and the last; the free space is recorded every frame")
      ->check(cli::positiveNumber());
  app->add_flag("--time-planning", options->time_planning,
                "also time a 100 000-point distance query and a batch rebuild of the\n"
                "planning layer (stats.json planning.query_100k_ms, planning.rebuild_ms)");
  app->add_option("--disparity-topic", options->bag_topics.disparity,
                  "a bag's disparity topic (default /stereo/disparity)")
      ->type_name("TOPIC");
  app->add_option("--image-topic", options->bag_topics.image,
                  "a bag's colour image topic (default /stereo/left/image_rect_color)")
      ->type_name("TOPIC");
  app->add_option("--camera-info-topic", options->bag_topics.camera_info,
                  "a bag's camera info topic (default /stereo/left/camera_info)")
      ->type_name("TOPIC");
  CLI::Option* world_frame = app->add_option("--world-frame", options->bag_topics.world_frame,
                                             "the world frame of a bag's /tf (default map)")
                                 ->type_name("FRAME");
  app->add_option("--load-map", options->load_map,
                  "start from a map saved with --save-map (same voxel_size_m, truncation_vox)")
      ->type_name("FILE");
  app->add_option("--save-map", options->save_map,
                  "save the map after the last frame (versioned binary, checksummed)")
      ->type_name("FILE");
  app->add_option("--trajectory", options->trajectory,
                  "a SLAM's corrected camera poses, TUM lines 'stamp tx ty tz qx qy qz qw' with\n"
                  "stamps matching the frames' (typically keyframes): after the last frame the\n"
                  "frames are fused again at the poses it implies (frames between two of its\n"
                  "poses take their interpolated correction), as after a loop closure")
      ->type_name("FILE");
  app->add_flag_callback(
      "--quiet", [options] { options->progress = false; }, "no progress output");
  app->callback([sources, options, world_frame] {
    std::string error;
    if (!applySources(*sources, world_frame->count() > 0, options, &error))
      throw CLI::ValidationError(error);
  });
}

bool parseFuseArguments(const std::vector<std::string>& args, FuseOptions* options,
                        std::string* error) {
  CLI::App app;
  addFuseArguments(&app, options);
  return cli::parseArguments(app, args, error);
}

}  // namespace stereo_fusion
