#pragma once
// An OBJ file read back (readers/ObjReader) in the form the rasteriser draws, so the comparison can
// render exactly what the export wrote.

#include <string>
#include <unordered_map>

#include "readers/ObjReader.h"
#include "stereo_fusion/mesh/SubMesh.h"
#include "stereo_fusion/mesh/TexturePatch.h"

namespace stereo_fusion::texcmp {

/// `obj`'s faces as submeshes keyed by a synthetic BlockKey {group, 0, 0}, one group per
/// (object, material) pair, triangle corners unwelded. Faces with texture coordinates and a
/// material with a diffuse map get a patch that is the whole atlas image (loaded once and
/// shared) with the OBJ's v flipped back to the image convention; others use the vertex
/// colours (white without). False with a message when an atlas cannot be read.
bool objToRenderable(const ObjMesh& obj,
                     std::unordered_map<BlockKey, SubMesh, BlockKeyHash>* meshes,
                     std::unordered_map<BlockKey, TexturePatch, BlockKeyHash>* patches,
                     std::string* error);

}  // namespace stereo_fusion::texcmp
