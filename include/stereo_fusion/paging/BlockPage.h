#pragma once
#include <cstdint>
#include <memory>
#include <string>

#include "stereo_fusion/io/ByteCodec.h"
#include "stereo_fusion/map/VoxelBlock.h"
#include "stereo_fusion/mesh/SubMesh.h"
#include "stereo_fusion/mesh/TexturePatch.h"

namespace stereo_fusion {

/// A paged-out block's page, as the BlockStore keeps it (machine-local, little-endian):
///   u32 magic "SFPG", u32 version; i32 x, y, z; u64 last update frame; u8 levels (bit l: level
///   l stored), then the stored levels' voxels as in memory (12 B each, level 0 first);
///   u32 layer count, then per registered layer (in registration order) u64 bytes + its part
///   (MapLayer::pageOut(): the mesh layer's submesh and texture patch; empty for a layer that
///   keeps its state in memory).
constexpr uint32_t kBlockPageMagic = 0x47504653u;  // "SFPG"
constexpr uint32_t kBlockPageVersion = 1;

/// Writes the page's head: the block's key, last update frame and voxels.
void writePageHead(const VoxelBlock& block, uint64_t last_update_frame, ByteWriter* out);
/// Reads a page head into a new block (outside any octree). nullptr with a sentence in `error`
/// when the page is not one, holds another key or is cut short.
std::unique_ptr<VoxelBlock> readPageHead(ByteReader* in, const BlockKey& expected,
                                         uint64_t* last_update_frame, std::string* error);
/// Skips a page head (a reader that wants only the layers' parts).
bool skipPageHead(ByteReader* in);

void writeSubMesh(const SubMesh& mesh, ByteWriter* out);
bool readSubMesh(ByteReader* in, SubMesh* mesh);
void writeTexturePatch(const TexturePatch& patch, ByteWriter* out);
bool readTexturePatch(ByteReader* in, TexturePatch* patch);

}  // namespace stereo_fusion
