#pragma once
#include <string>
#include <unordered_map>

#include "stereo_fusion/mesh/SubMesh.h"
#include "stereo_fusion/mesh/TexturePatch.h"

namespace stereo_fusion {

/// Writes the mesh held as submeshes (+ their texture patches) in the format the extension
/// names — `.obj`: OBJ + MTL + atlas PNGs (writeTexturedObj); anything else: binary PLY of the
/// welded submeshes — as the `save_mesh` services of the nodelet and the assembler promise
/// (srv/SaveMesh.srv). `message` says what was written, or why nothing was.
bool exportMesh(const std::string& path,
                const std::unordered_map<BlockKey, SubMesh, BlockKeyHash>& submeshes,
                const std::unordered_map<BlockKey, TexturePatch, BlockKeyHash>& patches,
                std::string* message);

}  // namespace stereo_fusion
