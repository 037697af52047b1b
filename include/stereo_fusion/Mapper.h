#pragma once
#include <deque>
#include <limits>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "stereo_fusion/MapperConfig.h"
#include "stereo_fusion/MapperStage.h"
#include "stereo_fusion/integration/BlockLookup.h"
#include "stereo_fusion/integration/FrameGate.h"
#include "stereo_fusion/integration/FreeSpaceCarver.h"
#include "stereo_fusion/integration/OutlierRejection.h"
#include "stereo_fusion/integration/ContradictionFilter.h"
#include "stereo_fusion/integration/DisparityNoise.h"
#include "stereo_fusion/integration/StereoFrame.h"
#include "stereo_fusion/integration/SurfaceFuser.h"
#include "stereo_fusion/io/MapFile.h"
#include "stereo_fusion/map/BlockChangeLog.h"
#include "stereo_fusion/map/BlockOctree.h"
#include "stereo_fusion/map/EvictionPolicy.h"
#include "stereo_fusion/map/MapRegion.h"
#include "stereo_fusion/mesh/MeshStore.h"
#include "stereo_fusion/mesh/TextureStore.h"
#include "stereo_fusion/planning/OccupancyGrid2D.h"
#include "stereo_fusion/planning/PlanningMap.h"
#include "stereo_fusion/util/ThreadPool.h"

namespace stereo_fusion {

/// What one meshing pass (Mapper::updateMesh()) did.
struct MeshPass {
  /// Submeshes changed / removed by this pass.
  MeshChanges mesh;
  /// What the texture pass did (all zero unless texture = patches).
  TextureStats texture;
  /// Blocks fusion or eviction changed since the previous pass: what this pass meshed around.
  size_t blocks_changed = 0;
};

/// What one planning update (Mapper::updatePlanning()) did.
struct PlanningPass {
  PlanningUpdateStats stats;
  double esdf_ms = 0.0;  ///< re-reading the changed TSDF blocks' cells and updating the ESDF
};

/// Block changes the planning layer may leave waiting in the map log (or 4 per block of the
/// map, if more) before integrate() updates it itself.
constexpr size_t kMaxPendingPlanningChanges = 1 << 16;

/// When integrate() brings the mesh up to date.
enum class MeshTiming {
  kNow,       ///< right after the frame (updateMesh()): the mesh always matches the map
  kDeferred,  ///< later, by the caller's updateMesh(): the frame's changes wait in the change log
};

/// What integrate() did with one frame.
struct IntegrationResult {
  bool accepted = false;  ///< false: the frame was rejected and the map is unchanged
  RejectReason reason = RejectReason::kNone;  ///< why it was rejected, for counters
  std::string error;                          ///< why it was rejected, one sentence
  /// Accepted only because the frames rejected before it agreed with it (FrameGate: a
  /// relocalisation or a clock reset); `note` says why.
  bool reanchored = false;
  std::string note;
  double lookup_ms =
      0.0;  ///< the frame's depths and colours, its disparity noise (DisparityNoise), the lookup
  double fusion_ms = 0.0;
  double carve_ms = 0.0;  ///< free-space carving (FreeSpaceCarver), included in nothing else
  double contradiction_ms = 0.0;  ///< ContradictionFilter, included in nothing else
  double free_space_ms =
      0.0;  ///< recording the space the frame saw empty (planning layer), included in nothing else
  FreeSpaceStats free_space;
  /// The planning layer was updated after this frame because its changes had piled up
  /// (kMaxPendingPlanningChanges), taking planning_catch_up_ms.
  bool planning_catch_up = false;
  double planning_catch_up_ms = 0.0;
  OutlierRejectionStats
      rejected;  ///< usable pixels the outlier rejection dropped (counted, not fused)
  /// Usable pixels dropped as isolated contradictions of confident surfaces (counted, not fused).
  ContradictionStats contradiction;
  /// The frame's disparity noise σ_d measured from its own disparities (DisparityNoise), px;
  /// NaN when it had too few usable samples or the frame was rejected before.
  double disparity_noise_px = std::numeric_limits<double>::quiet_NaN();
  LookupStats lookup;
  FusionStats fusion;
  CarveStats carve;
  /// Blocks whose voxels changed in this frame and were kept, sorted by key.
  std::vector<BlockKey> updated_blocks;
  /// Blocks evicted after this frame by the memory bound (max_blocks,
  /// max_distance_from_camera_m), sorted by key.
  std::vector<BlockKey> evicted_blocks;
  /// With MeshTiming::kNow (and meshing enabled): what the meshing pass after this frame
  /// changed (the submeshes of evicted blocks among the removed) and its texture pass.
  /// Empty with MeshTiming::kDeferred.
  MeshChanges mesh;
  TextureStats texture;
};

/// What clearRegion() did.
struct ClearResult {
  bool accepted =
      false;  ///< false: the region was invalid (`error` says why) and the map is unchanged
  std::string error;
  uint64_t blocks_visited = 0;  ///< blocks of the map the region reaches
  uint64_t blocks_changed = 0;  ///< blocks that lost observed voxels and keep some
  uint64_t blocks_erased = 0;   ///< blocks left without an observed voxel, erased
  uint64_t voxels_cleared = 0;  ///< observed voxels made unobserved, all levels
  double clear_ms = 0.0;
  /// As IntegrationResult::mesh and ::texture: with MeshTiming::kNow, what the meshing pass
  /// changed.
  MeshChanges mesh;
  TextureStats texture;
};

/// The ROS-free mapping pipeline. integrate(frame) = validate → lookup → fusion → eviction; every
/// stage after fusion learns which blocks changed from a change log (BlockChangeLog) and
/// catches up at its own rate: eviction after every frame, the mesher (and after it the texture
/// pass) whenever updateMesh() runs — after every frame by default, or as the caller chooses.
class Mapper {
 public:
  /// Throws std::invalid_argument listing every invalid parameter.
  explicit Mapper(const MapperConfig& config);

  /// Fuses one frame. A frame that fails validateFrame() is rejected with the reason and
  /// leaves the map untouched. With MeshTiming::kNow the mesh is brought up to date too.
  IntegrationResult integrate(const StereoFrame& frame, MeshTiming mesh_timing = MeshTiming::kNow);
  /// Meshes around every block changed since the last pass (nothing when meshing is disabled)
  /// and, with texture = patches, textures the changed submeshes from the latest frame.
  MeshPass updateMesh();
  /// Brings the planning layer's occupancy and distance field up to date with every TSDF change
  /// since the previous call (nothing without planning_enabled). Like updateMesh(), at the
  /// caller's rate: between calls the free space is recorded every frame, the rest waits in the
  /// map log (integrate() runs it when more than kMaxPendingPlanningChanges wait).
  PlanningPass updatePlanning();
  /// updatePlanning() in two halves. The first, with the map as for any call, reads the
  /// changed TSDF blocks' cells (nullopt without planning_enabled). The second touches only
  /// the planning layer: it may run on another thread while this Mapper integrates frames
  /// (their free space joins the layer when it ends), as long as the Mapper lives; `before_end`
  /// as PlanningMap::finishUpdate(). Until the second half ends, the first half's thread must
  /// not call integrate(), updatePlanning(), rebuildPlanning(), clears or encodeMap(): they
  /// wait for it.
  std::optional<PlanningMap::PendingUpdate> beginPlanningUpdate();
  PlanningPass finishPlanningUpdate(
      PlanningMap::PendingUpdate pending,
      const std::function<void(const PlanningPass&)>& before_end = {});
  /// Re-reads every TSDF block into the planning layer and recomputes its distance field from
  /// scratch (the same result as the incremental updates); returns its work.
  PlanningPass rebuildPlanning();
  /// The planning layer (free / occupied / unknown, the ESDF); nullptr without planning_enabled.
  /// Its readers are safe to call from any thread while this Mapper integrates.
  const PlanningMap* planning() const { return planning_ ? &*planning_ : nullptr; }
  /// Block changes (one per block and frame) recorded by fusion or eviction that the mesher has
  /// not caught up with yet. A caller that integrates with MeshTiming::kDeferred must call
  /// updateMesh() now and then: the changes wait in memory until it does.
  size_t blocksAwaitingMesh() const;
  /// The map's bytes (BlockOctree::memoryBytes()) without a walk over the blocks: cheap enough
  /// to report every frame under a lock.
  size_t memoryBytes() const;

  const BlockOctree& map() const { return octree_; }
  /// The incrementally maintained mesh, one submesh per block (current as of the last
  /// updateMesh()).
  const MeshStore& mesh() const { return mesh_store_; }
  /// The whole mesh, submeshes welded into one (for export).
  TriangleMesh extractMesh() const { return weldSubmeshes(mesh_store_.submeshes()); }
  /// Re-meshes every block from scratch (also what a disabled incremental mesher catches up with).
  MeshChanges rebuildMesh();
  /// Texture patches of the submeshes (empty unless texture = patches).
  const TextureStore& textures() const { return texture_store_; }
  const MapperConfig& config() const { return config_; }
  /// Frames accepted so far.
  uint64_t framesIntegrated() const { return frames_integrated_; }
  /// Where the last fused frame's camera was (nullopt before the first, after a reset or load).
  const std::optional<Eigen::Vector3d>& lastCameraPositionM() const {
    return gate_.lastFusedPosition();
  }
  /// The occupancy grid's window (grid_max_cells) around the last camera, or the origin.
  GridWindow occupancyGridWindow() const {
    GridWindow w;
    w.max_cells = config_.grid_max_cells;
    if (lastCameraPositionM()) w.centre_m = lastCameraPositionM()->head<2>();
    return w;
  }
  /// The median of the last kNoiseFrames frames' measured disparity noise (px), NaN before
  /// any: what /diagnostics and the warnings report. (The contradiction filter uses each
  /// frame's own estimate, so a map continued after a load fuses as if never interrupted.)
  double measuredDisparityNoisePx() const;
  static constexpr size_t kNoiseFrames = 31;
  /// The warning that disparity_noise_px is set finer than the frames measure (the measured
  /// median above 1.5× the configured value), empty when it is not. The estimate sees only the
  /// noise that varies from pixel to pixel, so it can say "noisier", never "finer".
  std::string disparityNoiseWarning() const;
  /// Blocks evicted by the memory bound since construction, reset() or loadMap().
  uint64_t blocksEvicted() const { return blocks_evicted_; }
  /// The frame that last updated `block` (the eviction order).
  uint64_t lastUpdateFrame(const VoxelBlock& block) const {
    return eviction_.lastUpdateFrame(block);
  }
  /// Drops the whole map.
  void reset();
  /// Forgets what the map holds in `region` (world frame): every observed voxel whose centre
  /// lies in it becomes unobserved, at every level; blocks left empty are erased (and their
  /// submeshes removed), the others re-meshed. Unknown space stays unknown: later frames fill
  /// the region again. An invalid region is refused and leaves the map untouched.
  ClearResult clearRegion(const MapRegion& region, MeshTiming mesh_timing = MeshTiming::kNow);

  /// A consumer of the mesh's changes (submeshes changed / removed by meshing passes, rebuilds,
  /// loads and resets), e.g. a publisher that sends them at its own rate. It must take them
  /// now and then: they wait in memory until it does.
  BlockChangeLog::Consumer subscribeToMeshChanges(const std::string& name) {
    return mesh_changes_.subscribe(name);
  }
  /// The submeshes changed (updated) and removed (erased) since `consumer` last took them.
  BlockChangeLog::Changes takeMeshChanges(BlockChangeLog::Consumer consumer) {
    return mesh_changes_.take(consumer);
  }
  /// Mesh changes recorded for `consumer` and not taken yet.
  size_t pendingMeshChanges(BlockChangeLog::Consumer consumer) const {
    return mesh_changes_.pending(consumer);
  }

  /// Writes the map to `path` (io/MapFile.h format, via a temporary file renamed into place).
  bool saveMap(const std::string& path, std::string* error) const;
  /// The bytes saveMap() writes, before their checksums (encodeMapFileUnsealed()): a copy, so
  /// that a caller holding a lock around the map can release it before writeMapFileBytes()
  /// checksums and writes them.
  std::vector<uint8_t> encodeMap() const;
  /// Replaces the map by the one in `path` and re-meshes it (the returned changes list every
  /// submesh of the new map as changed and every old one that is gone as removed). The file
  /// is read and checked completely into a fresh octree first: on any error (missing,
  /// truncated, corrupted, other version or voxel size) false with a message, and the current
  /// map and mesh are untouched.
  bool loadMap(const std::string& path, MeshChanges* changes, std::string* error);
  /// The second half of loadMap(): replaces the map by `loaded`, a map readMapFile() accepted
  /// for this mapper's config() (`loaded` then holds the old map), and re-meshes it. A caller
  /// holding a lock around the map can so read the file before taking it.
  MeshChanges adoptMap(BlockOctree* loaded, const MapFileInfo& info);
  /// Reports every operation's stage into `monitor` (nullptr: none) for a watchdog on another
  /// thread; the caller keeps it alive while this Mapper works.
  void setStageMonitor(StageMonitor* monitor) { monitor_ = monitor; }

 private:
  /// Records a meshing pass's (or rebuild's) changes for the mesh's consumers.
  void recordMeshChanges(const MeshChanges& changes);

  MapperConfig config_;
  ThreadPool pool_;
  BlockOctree octree_;
  MeasurementImage measurements_;  // the frame's depths and colours, read by lookup and fusion
  OutlierRejection outlier_rejection_;
  ContradictionFilter contradiction_;
  BlockLookup lookup_;
  SurfaceFuser fuser_;
  FreeSpaceCarver carver_;
  MeshStore mesh_store_;
  TextureStore texture_store_;
  EvictionPolicy eviction_;
  std::optional<PlanningMap> planning_;  // with planning_enabled only
  /// Blocks fusion updated and eviction erased, for the stages after fusion.
  BlockChangeLog map_changes_;
  BlockChangeLog::Consumer mesh_consumer_, eviction_consumer_;
  std::optional<BlockChangeLog::Consumer> planning_consumer_;  // with planning_enabled only
  /// Submeshes the mesher changed, for the texture pass and outside consumers.
  BlockChangeLog mesh_changes_;
  std::optional<BlockChangeLog::Consumer> texture_consumer_;  // with texture = patches only
  /// Bytes of allocated voxel levels, kept up to date as fusion allocates and eviction frees
  /// them, so memoryBytes() costs no walk over the blocks.
  size_t voxel_bytes_ = 0;
  /// The latest accepted frame: what a deferred meshing pass textures from.
  StereoFrame last_frame_;
  uint64_t frames_integrated_ = 0;
  std::deque<double> recent_noise_px_;  // the last kNoiseFrames frames' measured σ_d
  uint64_t blocks_evicted_ = 0;
  StageMonitor* monitor_ = nullptr;
  FrameGate gate_;
  std::vector<VoxelBlock*> queue_;                    // reused across frames
  std::vector<BlockKey> missing_;                     // reused across frames
  std::vector<VoxelBlock*> updated_;                  // reused across frames
  std::vector<VoxelBlock*> carved_;                   // reused across frames
  std::vector<std::unique_ptr<VoxelBlock>> created_;  // reused across frames
};

}  // namespace stereo_fusion
