#pragma once
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <unordered_set>
#include <vector>

#include "stereo_fusion/MapperConfig.h"
#include "stereo_fusion/MapperResults.h"
#include "stereo_fusion/MapperStage.h"
#include "stereo_fusion/StageConfigs.h"
#include "stereo_fusion/integration/FramePipeline.h"
#include "stereo_fusion/io/MapFile.h"
#include "stereo_fusion/layers/MapLayer.h"
#include "stereo_fusion/layers/MeshLayer.h"
#include "stereo_fusion/layers/PlanningLayer.h"
#include "stereo_fusion/map/BlockChangeLog.h"
#include "stereo_fusion/map/BlockColumn.h"
#include "stereo_fusion/map/BlockOctree.h"
#include "stereo_fusion/map/EvictionPolicy.h"
#include "stereo_fusion/map/MapRegion.h"
#include "stereo_fusion/paging/BlockStore.h"
#include "stereo_fusion/paging/CheckpointState.h"
#include "stereo_fusion/paging/FrameReach.h"
#include "stereo_fusion/paging/PageWriter.h"
#include "stereo_fusion/paging/PagedBlocks.h"
#include "stereo_fusion/paging/PagingConfig.h"
#include "stereo_fusion/planning/OccupancyGrid2D.h"
#include "stereo_fusion/util/ThreadPool.h"

namespace stereo_fusion {

/// The ROS-free map host. A frame goes through the FramePipeline (validation to carving), which
/// leaves its edit; the host applies it (the new blocks, the map's change log, eviction) and
/// then tells its layers (MapLayer: the mesh, the planning layer, any registered one), each of
/// which catches up with the log at its own cadence: the mesh whenever updateMesh() runs (after
/// every frame by default), the planning layer whenever updatePlanning() runs. The host owns
/// clear, reset, load and save; each layer clears, resets, saves and adopts its own part.
class Mapper {
 public:
  /// Throws std::invalid_argument listing every invalid parameter.
  explicit Mapper(const MapperConfig& config);

  /// Fuses one frame. A frame a stage refuses is rejected with the reason and leaves the map
  /// untouched. With MeshTiming::kNow the mesh is brought up to date too.
  IntegrationResult integrate(const StereoFrame& frame, MeshTiming mesh_timing = MeshTiming::kNow);
  /// Meshes around every block changed since the last pass (nothing when meshing is disabled)
  /// and, with texture = patches, textures the changed submeshes from the latest frame.
  MeshPass updateMesh();
  /// Brings the planning layer's occupancy and distance field up to date with every TSDF change
  /// since the previous call (nothing without planning_enabled). Between calls the free space
  /// is recorded every frame; the rest waits in the map log (integrate() runs it when more than
  /// kMaxPendingLayerChanges wait).
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
  const PlanningMap* planning() const { return planning_ ? &planning_->map() : nullptr; }

  /// Registers a layer (one class, one call): from now on it is told of every frame, clear,
  /// reset, save and load, and `updateLayer()` brings it up to date with the map's changes
  /// since its previous update. The map so far reaches it through rebuild(). Returns it.
  template <typename Layer>
  Layer& addLayer(std::unique_ptr<Layer> layer) {
    Layer& added = *layer;
    registerLayer(std::move(layer));
    return added;
  }
  /// Hands `layer` (registered) the map's block changes since its previous update.
  void updateLayer(MapLayer& layer);

  /// Block changes (one per block and frame) recorded by fusion or eviction that the mesher has
  /// not caught up with yet. A caller that integrates with MeshTiming::kDeferred must call
  /// updateMesh() now and then: the changes wait in memory until it does.
  size_t blocksAwaitingMesh() const;
  /// The map's bytes (BlockOctree::memoryBytes()) without a walk over the blocks: cheap enough
  /// to report every frame under a lock.
  size_t memoryBytes() const;

  /// The TSDF and colour layer: the blocks, their voxels at every level, their topology.
  const BlockOctree& tsdf() const { return octree_; }
  /// The incrementally maintained mesh, one submesh per block (current as of the last
  /// updateMesh()).
  const MeshStore& mesh() const { return mesh_->store(); }
  /// The whole mesh, submeshes welded into one (for export), paged-out blocks' included.
  TriangleMesh extractMesh() const;
  /// The submeshes and texture patches of the paged-out blocks (those among `only`, if given),
  /// read back from the block store (empty without paging): with mesh().submeshes() and
  /// textures().patches(), the whole mesh.
  struct PagedMeshParts {
    std::unordered_map<BlockKey, SubMesh, BlockKeyHash> submeshes;
    std::unordered_map<BlockKey, TexturePatch, BlockKeyHash> patches;
  };
  PagedMeshParts pagedMeshParts(const std::vector<BlockKey>* only = nullptr) const;
  /// A copy of every submesh and patch, paged-out ones included (for a full export or resend).
  PagedMeshParts wholeMesh() const;
  /// The keys of every submesh, paged-out ones included, sorted (reads no page).
  std::vector<BlockKey> submeshKeys() const;
  /// Re-meshes every block from scratch (also what a disabled incremental mesher catches up with).
  MeshChanges rebuildMesh();
  /// Texture patches of the submeshes (empty unless texture = patches).
  const TextureStore& textures() const { return mesh_->textures(); }
  const MapperConfig& config() const { return config_; }
  /// Frames accepted so far.
  uint64_t framesIntegrated() const { return frames_integrated_; }
  /// Where the last fused frame's camera was (nullopt before the first, after a reset or load).
  const std::optional<Eigen::Vector3d>& lastCameraPositionM() const {
    return pipeline_.lastFusedPosition();
  }
  /// The occupancy grid's window (grid_max_cells) around the last camera, or the origin.
  GridWindow occupancyGridWindow() const;
  /// The median of the last kNoiseFrames frames' measured disparity noise (px), NaN before
  /// any: what /diagnostics and the warnings report. (The contradiction filter uses each
  /// frame's own estimate, so a map continued after a load fuses as if never interrupted.)
  double measuredDisparityNoisePx() const { return pipeline_.measuredDisparityNoisePx(); }
  static constexpr size_t kNoiseFrames = FramePipeline::kNoiseFrames;
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
    return mesh_->subscribe(name);
  }
  /// The submeshes changed (updated) and removed (erased) since `consumer` last took them.
  BlockChangeLog::Changes takeMeshChanges(BlockChangeLog::Consumer consumer) {
    return mesh_->take(consumer);
  }
  /// Mesh changes recorded for `consumer` and not taken yet.
  size_t pendingMeshChanges(BlockChangeLog::Consumer consumer) const {
    return mesh_->pending(consumer);
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
  /// Waits until every page handed to the store's writer is written (or refused: then its
  /// blocks are back in memory and paging has stopped). Paging works without it; a caller that
  /// reports pagingStats() or measures the store calls it first.
  void flushPaging();
  /// Paging (max_map_memory_mb): what it did since the map was made, reset or loaded.
  const PagingStats& pagingStats() const { return paging_stats_; }
  /// Blocks paged out now (in the block store, not in memory): tsdf() holds the others.
  size_t pagedOutBlocks() const { return paged_.size(); }
  /// Bytes every layer holds in memory (the TSDF, the mesh and its textures, the planning
  /// layer): what max_map_memory_mb caps. O(1) but for the textures.
  size_t mapMemoryBytes() const;
  /// The map store (checkpoint_period_s, resume; MapperCheckpoint.cpp): map_store_path/
  /// map.sqlite, the map's durable copy. Separate from the paging store (a cache of this
  /// process), it changes only by whole checkpoints, one transaction each, so after a kill it
  /// holds the map of its last committed checkpoint.
  struct StoreOpening {
    bool ok = false;       ///< false: `message` says why; the map is unchanged and has no map store
    bool resumed = false;  ///< the map is the store's
    std::string message;   ///< one sentence for the log
    std::string owner_note;  ///< the owner's note of the resumed checkpoint
    MeshChanges changes;     ///< resumed: every submesh of the map, and the old ones removed
  };
  /// Opens the map store; `resume`: the map becomes the one it holds (as at its last
  /// checkpoint: voxels, mesh and patches, the planning layer derived again) and later frames
  /// continue it as if never interrupted. Without `resume` a map it held is replaced at the
  /// first checkpoint. A store that cannot be read, or of another voxel grid, is refused and
  /// left untouched.
  StoreOpening openMapStore(bool resume);
  /// Hands the map store every block changed since the previous checkpoint (their pages, the
  /// blocks gone, the map's counters and seen-free space, `owner_note`): its thread writes
  /// them in one transaction. False (with `error`) without a map store or after the store
  /// refused an earlier checkpoint (reported once; the next one rewrites the store whole).
  bool checkpoint(const std::string& owner_note, std::string* error);
  /// Waits until every checkpoint handed over is committed (or refused).
  void flushCheckpoints();
  bool hasMapStore() const { return map_store_ != nullptr; }
  /// The checkpoints committed so far, as of the last frame (flushCheckpoints(): the latest).
  const CheckpointStats& checkpointStats() const { return checkpoint_stats_; }
  /// Gives the map store to `to`, a map that replaces this one (a loop closure's rebuild): its
  /// next checkpoint rewrites the store whole.
  void handOverMapStore(Mapper* to);
  /// Reports every operation's stage into `monitor` (nullptr: none) for a watchdog on another
  /// thread; the caller keeps it alive while this Mapper works.
  void setStageMonitor(StageMonitor* monitor) { monitor_ = monitor; }

 private:
  struct LayerSlot {
    std::unique_ptr<MapLayer> layer;
    BlockChangeLog::Consumer consumer;
  };
  void registerLayer(std::unique_ptr<MapLayer> layer);
  BlockChangeLog::Consumer consumerOf(const MapLayer& layer) const;
  /// The frame's new blocks join the map, its changes the log; then the memory bound.
  void applyEdit(const StereoFrame& frame, IntegrationResult* result);
  /// updateMesh() without the page-out that follows it.
  MeshPass meshPass();
  /// The layers' per-frame hooks, and the update of any layer whose changes piled up.
  void tellLayers(const StereoFrame& frame, StageScope* stage, IntegrationResult* result);

  // Paging (MapperPaging.cpp): every block within one block of a change a layer has not taken
  // is in memory when the layer takes it (the mesh's and the mesh consumers' stay in memory;
  // a lagging layer's may be paged out and come back before its update), so a layer's update
  // never meets a paged-out block; a frame, an eviction or a clear first brings back the
  // blocks it can reach.
  /// Opens the block store (with max_map_memory_mb).
  void openStore();
  /// The paged-out blocks `frame` can change or mesh around (FrameReach) come back.
  void pageInReach(const StereoFrame& frame);
  /// The paged-out blocks within one block of `keys` come back.
  void pageInAround(const std::vector<BlockKey>& keys);
  void pageInAll();
  /// Brings back the paged-out blocks of `keys` (sorted; keys not paged out are skipped).
  /// `in_use`: something needs these very blocks (a frame reaches them, a mesh pass meshes
  /// around them), so they leave after the blocks nothing used since; a whole-map pass brings
  /// blocks back without that.
  void pageIn(const std::vector<BlockKey>& keys, bool in_use = true);
  /// When a page-out pass runs: after a frame (or another operation) any block may leave, the
  /// last frame's reach last; before a frame fuses, none it reaches (the frame is about to
  /// read and write them) — what the frame brought back makes room for itself first.
  enum class PageOutWhen { kAfter, kBeforeFrame };
  /// Over max_map_memory_mb, pages out the blocks that leave first (leavesFirst()) that no
  /// layer's pending change reaches, down to kHysteresis below the cap.
  void pageOutOverCap(PageOutWhen when = PageOutWhen::kAfter);
  /// The blocks a page-out of `to_free` bytes takes, in leavesFirst() order, with their last
  /// update frames; returns the bytes they free (less than asked when too many must stay).
  /// `keep_lagging`: also keep what a layer that catches up itself has not taken.
  size_t selectPageOut(size_t to_free, bool keep_lagging, PageOutWhen when,
                       std::vector<BlockKey>* keys, std::vector<uint64_t>* frames) const;
  /// The changes `consumer` has not taken, once every block within one block of them is back.
  BlockChangeLog::Changes takeChanges(BlockChangeLog::Consumer consumer);
  /// The page of a paged-out block, read without bringing it back; false when unreadable.
  /// `batch`: the read snapshot, begun after the writer released its written pages.
  bool readPage(const BlockKey& key, std::vector<uint8_t>* page, BlockStore::ReadBatch* batch,
                std::string* error) const;
  /// How much of a page placePage() brought back.
  enum class Placed { kWhole, kVoxelsOnly, kLost };
  /// What paging keeps of a resident block.
  struct PageState {
    /// The frame count when it last came back from the store: a block a frame reached is as
    /// recently used as one it updated, so it does not leave before blocks nothing used.
    uint64_t paged_in_frame = 0;
    /// The store's page of it is its page (nothing changed it since it came back): a page-out
    /// drops it without writing.
    bool page_current = false;
  };
  /// A block's rank in the paging order (leavesFirst()'s first key): its last use, updated or
  /// brought back.
  uint64_t lastUseFrame(const VoxelBlock& block) const;
  /// Puts the block of a page (`data`, `size`) into the octree and its parts into the layers;
  /// `error` says what could not be read.
  Placed placePage(const BlockKey& key, const uint8_t* data, size_t size, std::string* error);
  /// A resident block's page: its voxels and every layer's part (MapLayer::savePart()).
  void encodePage(const VoxelBlock& block, uint64_t last_update_frame,
                  std::vector<uint8_t>* bytes) const;
  /// Subscribes the stores' consumers of the map's and the mesh's changes (once).
  void subscribeStoreConsumers();
  /// Takes the map's and the mesh's changes since the last call: into the checkpoint's set,
  /// and out of the blocks whose paging-store page is current.
  void noteStoreChanges();
  /// A resident block's paging state (page_state_, fitted to the map).
  PageState& pageState(const VoxelBlock& block);
  /// The keys of every block of the map, resident or paged out, sorted.
  std::vector<BlockKey> allBlockKeys() const;
  /// Reads the map store's blocks and checkpoint record into this (emptied) map.
  bool resumeFrom(BlockStore* store, StoreOpening* out);
  /// Counts what the map store committed; reports a refused checkpoint.
  void foldCommittedCheckpoints();
  /// Counts a page that cannot be read back (its block is lost).
  void pageLost(const BlockKey& key, const std::string& why);
  /// Drops every page (reset, load).
  void forgetPages();
  /// After the writer's store refused a batch (a full disk): its blocks come back, paging stops.
  void recoverRefusedPages();

  const MapperConfig config_;
  const StageConfigs stages_;
  ThreadPool pool_;
  BlockOctree octree_;
  FramePipeline pipeline_;
  FrameEdit edit_;  // the frame's edit, reused across frames
  EvictionPolicy eviction_;
  /// Blocks fusion updated and eviction erased, for eviction and the layers.
  BlockChangeLog map_changes_;
  BlockChangeLog::Consumer eviction_consumer_;
  std::vector<LayerSlot> layers_;  // in registration order
  MeshLayer* mesh_ = nullptr;
  PlanningLayer* planning_ = nullptr;  // with planning_enabled only
  /// Bytes of allocated voxel levels, kept up to date as fusion allocates and eviction frees
  /// them, so memoryBytes() costs no walk over the blocks.
  size_t voxel_bytes_ = 0;
  uint64_t frames_integrated_ = 0;
  uint64_t blocks_evicted_ = 0;
  StageMonitor* monitor_ = nullptr;
  std::unique_ptr<BlockStore> store_;   // with max_map_memory_mb only: the map's reads
  std::unique_ptr<PageWriter> writer_;  // its writes, on a thread (destroyed before store_)
  PagedBlocks paged_;
  PagingStats paging_stats_;
  BlockColumn<PageState> page_state_;
  /// Where the last frame could reach: the next frames look about there, so a block in it stays
  /// while others can leave (selectPageOut()).
  std::optional<FrameReach> last_reach_;
  // The map store (MapperCheckpoint.cpp).
  std::unique_ptr<PageWriter> map_store_;  // its connection, writing checkpoints on its thread
  // Both stores' consumers of the map's and the mesh's changes (noteStoreChanges()).
  std::optional<BlockChangeLog::Consumer> store_map_consumer_;
  std::optional<BlockChangeLog::Consumer> store_mesh_consumer_;
  /// Blocks whose page changed since the last checkpoint (their TSDF, submesh or patch).
  std::unordered_set<BlockKey, BlockKeyHash> checkpoint_dirty_;
  /// The next checkpoint rewrites the store whole (a new map over it, a reset, a load).
  bool checkpoint_full_ = false;
  struct CheckpointInFlight {
    uint64_t batch;
    uint64_t frames_integrated;
    size_t blocks_written, blocks_erased, bytes_written;
    std::chrono::steady_clock::time_point started;
  };
  std::deque<CheckpointInFlight> checkpoints_in_flight_;
  CheckpointStats checkpoint_stats_;
};

}  // namespace stereo_fusion
