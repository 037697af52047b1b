#include "evaluator/HeldOutSelection.h"

#include <algorithm>
#include <charconv>
#include <sstream>

namespace stereo_fusion::eval {

bool parseHeldOutFrames(const std::string& spec, size_t frame_count, std::vector<size_t>* frames,
                        std::string* error) {
  frames->clear();
  if (spec == "odd" || spec == "even") {
    for (size_t i = spec == "odd" ? 1 : 0; i < frame_count; i += 2) frames->push_back(i);
  } else {
    std::istringstream items(spec);
    std::string item;
    while (std::getline(items, item, ',')) {
      // Allow "1, 3" as well as "1,3".
      item.erase(0, item.find_first_not_of(" \t"));
      item.erase(item.find_last_not_of(" \t") + 1);
      size_t index = 0;
      const char* end = item.data() + item.size();
      const auto [parsed_end, ec] = std::from_chars(item.data(), end, index);
      if (item.empty() || ec != std::errc() || parsed_end != end) {
        *error = "--held-out: \"" + item + "\" is not a frame index (expected odd, even or i,j,k)";
        return false;
      }
      if (index >= frame_count) {
        *error = "--held-out: frame " + item + " does not exist (the sequence has " +
                 std::to_string(frame_count) + " frames)";
        return false;
      }
      frames->push_back(index);
    }
    std::sort(frames->begin(), frames->end());
    frames->erase(std::unique(frames->begin(), frames->end()), frames->end());
  }
  if (frames->empty()) {
    *error = "--held-out \"" + spec + "\" selects no frames (the sequence has " +
             std::to_string(frame_count) + " frames)";
    return false;
  }
  return true;
}

}  // namespace stereo_fusion::eval
