#pragma once
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "stereo_fusion/map/BlockColumn.h"
#include "stereo_fusion/map/BlockOctree.h"
#include "stereo_fusion/mesh/SubMesh.h"

namespace stereo_fusion {

/// What the mesher needs from the configuration.
struct MeshingParams {
  double voxel_size_m = 0.02;
  /// Φ of a level = truncation_vox · s · voxel_size_m: a sign change between two values that
  /// are both at least 0.99·Φ away from zero is the edge of a truncation band, not a surface
  /// (Φ of the coarsest level among the blocks involved, to never drop a real surface).
  double truncation_vox = 4.0;
  /// A block is sampled at the finest level whose observed area is at least this share of
  /// the largest observed area among its levels (see chooseMeshLevel()).
  double level_min_coverage = 0.8;
  /// Close the seams between levels: an unobserved voxel on a face of a block meshed at a
  /// finer level than its coarsest takes the value of the block's own coarser levels there
  /// (see fillFacesFromCoarserLevels()). false: such voxels stay unobserved (cells touching
  /// them are skipped and leave a hole where a fine block meets a coarse one).
  bool fill_faces_from_coarser_levels = true;
};

/// What the mesher keeps per block, in a BlockColumn that MeshStore owns: derived from the
/// block's voxels by refreshMeshLevel() whenever fusion changed them, read for the owner and
/// its neighbours by every meshing pass.
struct MeshBlockState {
  /// Level the block is sampled at (chooseMeshLevel()).
  int8_t level = kNumLevels - 1;
  /// Which signs the observed voxels of `level` hold, per region of the block: an owner
  /// whose neighbourhood has one sign cannot contain a surface. Region 0 is the whole block;
  /// region r = 1..7 is what the mesher may read of this block for the owner at offset −r
  /// (bit a of r set: x/y/z towards −): the voxels whose centres lie within 4 finest voxels of
  /// the faces towards that owner. Bit 2r: some voxel < 0; bit 2r+1: some voxel ≥ 0
  /// (see meshSignBit()). Set by refreshMeshSigns().
  uint16_t sign_bits = 0;
  /// True: the block is meshed with its faces filled from its coarser levels
  /// (fillFacesFromCoarserLevels() filled some voxel). The copy is not kept: the mesher
  /// rebuilds it per owner in scratch (meshVoxels()), which costs less than the ~20 % of the
  /// map's memory that keeping it took.
  bool seam_filled = false;
};
using MeshStates = BlockColumn<MeshBlockState>;
/// Face-filled copies (fillFacesFromCoarserLevels()) of the seam-filled blocks a meshing pass
/// reads, built once per pass; an empty entry is built by the mesher when it needs it.
using SeamFills = BlockColumn<std::vector<Voxel>>;

/// The bit of MeshBlockState::sign_bits saying that region `region` (0..7) holds an observed
/// voxel < 0 (`non_negative` false) or ≥ 0 (true).
constexpr uint16_t meshSignBit(int region, bool non_negative) {
  return static_cast<uint16_t>(1u << (2 * region + (non_negative ? 1 : 0)));
}

/// The trilinear interpolation of one level's voxels (`side`³ of them) in the cell starting at
/// voxel i0 with fractions `frac` (0..1 inside the cell; beyond it, linear extrapolation):
/// signed distance and colour. False if a voxel with non-zero weight is unobserved. The one
/// weighted sum of the mesher's samples (blockField()) and the seam fill.
inline bool trilinearVoxels(const Voxel* voxels, int side, const int i0[3], const float frac[3],
                            float* sdf, float rgb[3]) {
  float acc = 0.0f, acc_rgb[3] = {0, 0, 0};
  for (int c = 0; c < 8; ++c) {
    const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
    const float w = (dx ? frac[0] : 1.0f - frac[0]) * (dy ? frac[1] : 1.0f - frac[1]) *
                    (dz ? frac[2] : 1.0f - frac[2]);
    if (w == 0.0f) continue;
    const Voxel& v = voxels[VoxelBlock::indexInLevel(side, i0[0] + dx, i0[1] + dy, i0[2] + dz)];
    if (!(v.weight > 0.0f)) return false;
    acc += w * v.sdf_m;
    acc_rgb[0] += w * v.r;
    acc_rgb[1] += w * v.g;
    acc_rgb[2] += w * v.b;
  }
  *sdf = acc;
  for (int k = 0; k < 3; ++k) rgb[k] = acc_rgb[k];
  return true;
}

/// What the mesher samples of `block`: its voxels at state.level, or (state.seam_filled) their
/// face-filled copy, built in `scratch`.
const Voxel* meshVoxels(const VoxelBlock& block, const MeshBlockState& state,
                        std::vector<Voxel>* scratch);

/// Fills `*out` with the voxels of `level` in which every unobserved voxel on the block's
/// faces (i, j or k = 0 or side − 1) takes the trilinear field of the block's next coarser level
/// whose voxels around that centre are observed, extrapolated linearly beyond the coarser
/// level's outer centres (a signed distance is locally linear; clamping would bend a surface
/// that meets the face obliquely): sdf and colour, weight 1 to mark it observed. A measurement
/// updates its own level and every coarser one, so a block seen partly from near and partly
/// from far holds coarse values near its faces where its fine voxels are empty: filled, the
/// fine block meets its coarse neighbour without a hole. Depends on the block alone, so the
/// owners of a seam agree. Returns false, with `*out` empty, when no voxel was filled.
bool fillFacesFromCoarserLevels(const VoxelBlock& block, int level, std::vector<Voxel>* out);

/// The level a block is meshed at: the finest level whose observed surface area (observed
/// voxels × voxel volume ÷ band thickness, ∝ n·s²) is at least `level_min_coverage` × the
/// largest of its levels'. A block seen only from far meshes at 2³, one seen from near at 8³, and
/// one seen from near in only a corner of what was seen from far stays coarse rather than opening
/// holes.
int chooseMeshLevel(const VoxelBlock& block, double level_min_coverage);

/// Sets state->sign_bits from the observed voxels of meshVoxels(block, *state, …).
void refreshMeshSigns(const VoxelBlock& block, MeshBlockState* state);

/// Sets state->level (chooseMeshLevel), its face fill (fillFacesFromCoarserLevels(), when
/// params.fill_faces_from_coarser_levels) and then its sign bits (refreshMeshSigns()).
/// Runs for every updated block before it is meshed, so on CPUs with AVX2 it takes the AVX2 path.
/// With `fill`, the face-filled copy is left there (empty when the block is not seam-filled)
/// for the pass's owners to read, instead of in a scratch of the thread.
void refreshMeshLevel(const VoxelBlock& block, const MeshingParams& params, MeshBlockState* state,
                      std::vector<Voxel>* fill = nullptr);

/// refreshMeshLevel() as written: chooseMeshLevel(), the fill, then refreshMeshSigns(). The
/// reference the AVX2 path is tested against.
void refreshMeshLevelScalar(const VoxelBlock& block, const MeshingParams& params,
                            MeshBlockState* state, std::vector<Voxel>* fill = nullptr);

/// Same level, fill and sign bits as refreshMeshLevelScalar(), eight voxels per step, counting
/// each level once and reading signs of the meshed voxels only. Only call it when avx2Supported().
void refreshMeshLevelAvx2(const VoxelBlock& block, const MeshingParams& params,
                          MeshBlockState* state, std::vector<Voxel>* fill = nullptr);

/// Which of BlockMesher's paths mesh a neighbourhood. Production meshes with kFast; kGeneralOnly
/// exists for tests: every box of every neighbourhood through the general path (every point
/// sampled by the general sampler, no owner skipped on its sign bits), the reference the fast
/// paths must match bit for bit (test_block_mesher_fast_paths).
enum class MesherPaths {
  kFast,         // uniform and mixed fast paths, owners skipped on their sign bits
  kGeneralOnly,  // tests only: the general path alone
};

/// Marching cubes for one block (thesis §3.6, Algorithm 3), crack-free across blocks of any
/// levels.
///
/// Geometry. The mesher works on an integer lattice of half-finest-voxel units (a block is
/// 16 units wide). A block sampled at level m (step s = 2^m) has its voxel centres at
/// s·(2i+1). Its cube is cut by those centre planes and by its own faces into (8/s + 1)³
/// boxes: the core boxes between centres, and half-voxel "skin" boxes between the outermost
/// centres and the faces. Values on a block face, edge or corner are the 1/s-weighted mean
/// of the touching blocks' fields (trilinear, clamped to each block's centres), so every
/// block computes the same number at a shared point; between two blocks of one level this
/// is exactly the linear interpolation along the classic seam cube's edge.
///
/// Ownership (Algorithm 3). A block owns its core and skin boxes on its +x/+y/+z side and
/// the −x/−y/−z skin boxes of its +x/+y/+z neighbours (face slabs, edge columns, corner):
/// the thesis' seam cubes, each split in two at the block face. A submesh therefore
/// depends only on the block and its 7 neighbours towards +x/+y/+z.
///
/// Different levels. A box face on a block face is tiled by the grid of both blocks'
/// centre lines, and every lattice point on a box edge (from any block touching that edge)
/// becomes a polygon corner. Both sides of every shared face thus see identical polygons,
/// and CellPolygonizer's face rule makes their traces identical: no cracks, no overlaps,
/// with no transition tables. Boxes with no extra corners use the 256-case table.
///
/// Cells with an unobserved corner are skipped (thesis), as are cells whose only sign
/// changes are between truncated values. Normals: area-weighted mean of the submesh's face
/// normals. Colours: the fused voxel colour, interpolated like the position (method A).
///
/// Speed (output unchanged bit for bit): each lattice point is sampled once per owner (a
/// dense per-owner grid over the coordinates in use); core boxes are pre-tested on the
/// owner's voxel signs; every box is rejected on its 8 corners before any hanging-point
/// work; hanging points come from per-owner bit masks; scratch buffers are per thread.
/// Uniform neighbourhoods visit only boxes whose support changes sign (row bit masks) and
/// sample voxels by index; mixed ones reject boxes with an unobserved corner or one sign on
/// per-block voxel masks before sampling; edge → vertex is a flat stamped table (in uniform
/// neighbourhoods a direct one indexed by grid point and axis, and only the crossing edges
/// are tested for the truncation band). The general path stays reachable for tests
/// (MesherPaths::kGeneralOnly), which compare the two.
///
/// Sources: BlockMesher.cpp (the neighbourhood and the choice of path) over src/mesh/Mesher*:
/// the lattice and its tables, the per-thread scratch and per-owner context, the sampler, the
/// general, uniform and mixed paths.
class BlockMesher {
 public:
  explicit BlockMesher(const MeshingParams& params, MesherPaths paths = MesherPaths::kFast);

  /// Meshes everything `owner` owns; neighbours are looked up in `map`. The states of the
  /// owner and its neighbours must be current. `seam_fills` (optional) holds the face-filled
  /// copies of seam-filled blocks prepared for the pass (MeshStore builds each once per pass).
  void mesh(const BlockOctree& map, const MeshStates& states, const VoxelBlock& owner, SubMesh* out,
            const SeamFills* seam_fills = nullptr) const;

 private:
  MeshingParams params_;
  MesherPaths paths_;
};

}  // namespace stereo_fusion
