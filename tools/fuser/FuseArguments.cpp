// The fuser's command line (parseFuseArguments()): flags, --config, --set.
#include <algorithm>
#include <stdexcept>

#include "fuser/OfflineFuser.h"
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

}  // namespace

bool parseFuseArguments(const std::vector<std::string>& args, FuseOptions* options,
                        std::string* error) {
  std::vector<std::string> positional, sets;
  std::string config_file;
  bool world_frame_given = false;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto value = [&](const char* flag) -> const std::string* {
      if (i + 1 >= args.size()) {
        *error = std::string(flag) + " needs a value";
        return nullptr;
      }
      return &args[++i];
    };
    if (a == "--config") {
      const std::string* v = value("--config");
      if (!v) return false;
      config_file = *v;
    } else if (a == "--set") {
      const std::string* v = value("--set");
      if (!v) return false;
      sets.push_back(*v);
    } else if (a == "--frames" || a == "--mesh-every" || a == "--esdf-every") {
      const std::string* v = value(a.c_str());
      if (!v) return false;
      const bool mesh_every = a != "--frames";  // a period: at least 1
      try {
        size_t used = 0;
        const long n = std::stol(*v, &used);
        if (used != v->size() || n < (mesh_every ? 1 : 0)) throw std::invalid_argument("");
        (a == "--mesh-every"   ? options->mesh_every
         : a == "--esdf-every" ? options->esdf_every
                               : options->max_frames) = static_cast<size_t>(n);
      } catch (...) {
        *error = a + ": '" + *v + "' is not a " + (mesh_every ? "frame count ≥ 1" : "frame count");
        return false;
      }
    } else if (a == "--disparity-topic" || a == "--image-topic" || a == "--camera-info-topic" ||
               a == "--world-frame") {
      const std::string* v = value(a.c_str());
      if (!v) return false;
      world_frame_given = world_frame_given || a == "--world-frame";
      (a == "--disparity-topic"     ? options->bag_topics.disparity
       : a == "--image-topic"       ? options->bag_topics.image
       : a == "--camera-info-topic" ? options->bag_topics.camera_info
                                    : options->bag_topics.world_frame) = *v;
    } else if (a == "--load-map" || a == "--save-map" || a == "--trajectory" ||
               a == "--frame-log") {
      const std::string* v = value(a.c_str());
      if (!v) return false;
      (a == "--load-map"    ? options->load_map
       : a == "--save-map"  ? options->save_map
       : a == "--frame-log" ? options->frame_log
                            : options->trajectory) = *v;
    } else if (a == "--quiet") {
      options->progress = false;
    } else if (a == "--time-planning") {
      options->time_planning = true;
    } else if (!a.empty() && a[0] == '-') {
      *error = "unknown option '" + a + "'";
      return false;
    } else {
      positional.push_back(a);
    }
  }
  if (positional.size() == 1 && !options->load_map.empty()) {
    options->out_dir = positional[0];  // mesh a saved map, no frames
  } else if (positional.size() == 2) {
    options->input = positional[0];
    options->out_dir = positional[1];
  } else {
    *error = "expected <seq-folder | file.bag> <out-dir> (or <out-dir> with --load-map), got " +
             std::to_string(positional.size()) + " arguments";
    return false;
  }
  if (!options->trajectory.empty() && options->input.empty()) {
    *error = "--trajectory needs the frames it corrects (an input folder or bag)";
    return false;
  }
  // The nodelet's own keys are accepted beside the mapping parameters (one YAML for both).
  const std::vector<std::string> node_names = nodeParameterNames();
  if (!config_file.empty()) {
    OtherParameters node_keys{node_names, {}};
    if (!loadMapperConfigFile(config_file, &options->config, error, &node_keys) ||
        !applyNodeParameters(node_keys.found, config_file, world_frame_given, options, error))
      return false;
  }
  std::vector<std::pair<std::string, std::string>> node_sets;
  for (const std::string& s : sets) {
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

}  // namespace stereo_fusion
