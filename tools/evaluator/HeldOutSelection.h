#pragma once
// Parsing of the --held-out frame selection.

#include <string>
#include <vector>

namespace stereo_fusion::eval {

/// Turns "odd", "even" or a comma-separated list of frame indices ("3,10,17") into sorted,
/// distinct indices, all < `frame_count`. Returns false with a reason for an empty or
/// malformed spec, an index out of range, or a selection with no frames.
bool parseHeldOutFrames(const std::string& spec, size_t frame_count, std::vector<size_t>* frames,
                        std::string* error);

}  // namespace stereo_fusion::eval
