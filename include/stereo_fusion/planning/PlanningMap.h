#pragma once
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <shared_mutex>
#include <utility>
#include <variant>
#include <vector>

#include <Eigen/Core>

#include "stereo_fusion/MapperConfig.h"
#include "stereo_fusion/map/BlockOctree.h"
#include "stereo_fusion/map/MapRegion.h"
#include "stereo_fusion/planning/EsdfPropagator.h"
#include "stereo_fusion/planning/EsdfTransit.h"
#include "stereo_fusion/planning/FreeSpaceRecorder.h"
#include "stereo_fusion/planning/PlanningBlock.h"
#include "stereo_fusion/planning/TsdfOccupancy.h"

namespace stereo_fusion {

/// The planning layer's parameters (from the parameter table's esdf_* / occupancy_* entries:
/// StageConfigs).
struct PlanningConfig {
  double cell_m = 0.08;             ///< MapperConfig::planningCellSizeM()
  int voxels_per_cell = 4;          ///< cell_m / voxel_size_m: 1, 2, 4 or 8
  double max_distance_m = 2.0;      ///< esdf_max_distance_m
  double unmeasured_range_m = 0.0;  ///< free_space_unmeasured_range_m
  float min_weight = 2.0f;          ///< occupancy_min_weight
  TruncationBand band{0.02, 4.0};
};

/// One answer of the distance field at a point.
struct EsdfSample {
  CellState state = CellState::kUnknown;
  /// Signed distance in metres between the cell's centre and its site's (positive outside
  /// obstacles, negative inside); NaN where the state is unknown; ±max_distance_m where no site
  /// lies within it.
  double distance_m = 0.0;
  /// Trilinear interpolation of the 8 cell centres around the point and its gradient, when all
  /// 8 are known (`interpolated`); otherwise distance_m and a zero gradient.
  double interpolated_m = 0.0;
  Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
  bool interpolated = false;
};

struct PlanningUpdateStats {
  uint64_t tsdf_blocks = 0;  ///< TSDF blocks whose cells were re-read
  uint64_t blocks_allocated = 0, blocks_erased = 0;
  uint64_t transit_allocated =
      0;  ///< of those allocated, blocks without a known cell (EsdfTransit)
  EsdfStats esdf;
  double read_ms = 0.0;       ///< re-reading the TSDF blocks' cells
  double propagate_ms = 0.0;  ///< the ESDF's wavefronts
  double transit_ms = 0.0;    ///< finding the transit blocks (EsdfTransit)
};

/// The planning layer: for every planning cell of space the frames have seen, what it is
/// (occupied / free / unknown, PlanningBlock) and its signed distance to the nearest obstacle
/// (EsdfPropagator). A layer beside the mesher: it follows the TSDF through the map log (the
/// TSDF blocks changed since its last update), and adds what only the frames know — the space
/// they saw empty beyond the TSDF's bands (FreeSpaceRecorder).
///
/// Writers run on the integrating thread (but for finishUpdate(), below); readers (state(),
/// sample(), sampleBatch(), the visitors) may run on any thread at any time: a shared lock guards
/// the blocks, and each writer holds it exclusively only while it changes them.
///
/// An update may also run in two halves (beginUpdate(), then finishUpdate() on any thread):
/// the first reads the TSDF and needs the octree, the second — the distance field's
/// wavefronts, most of the time — needs only this layer, so the node runs it without the map
/// lock while frames are fused. Updates finish in the order they began; the free space a frame
/// records meanwhile (recordFreeSpace(), dropFartherThan()) is kept in order and added when
/// the update finishes, as if the frame had come after it, which it did; clears, rebuild and
/// seenFree() wait for it.
class PlanningMap {
 public:
  PlanningMap(const PlanningConfig& config, ThreadPool* pool);

  const PlanningConfig& config() const { return config_; }
  const PlanningGrid& grid() const { return grid_; }

  // Writers.
  /// Records the space `frame` saw empty; returns the work done.
  FreeSpaceStats recordFreeSpace(const StereoFrame& frame, const MeasurementImage& measurements);
  /// Re-reads the cells of TSDF blocks `updated` (present in `octree`) and `erased`, then brings
  /// the distance field up to date with every change since the previous update.
  PlanningUpdateStats update(const BlockOctree& octree, const std::vector<BlockKey>& updated,
                             const std::vector<BlockKey>& erased);
  /// update()'s first half: the cells of TSDF blocks `updated` and `erased`, read from
  /// `octree` (which must not change meanwhile). Waits for an update begun before it to
  /// finish; until finishUpdate(), frame writes are kept for its end.
  class PendingUpdate;
  PendingUpdate beginUpdate(const BlockOctree& octree, const std::vector<BlockKey>& updated,
                            const std::vector<BlockKey>& erased);
  /// update()'s second half, on any thread: reads no octree. `before_end` runs after the
  /// distance field is updated and before the frame writes kept for it are added: readers
  /// called from it see exactly this update's layer. It must not wait for the update (clears,
  /// rebuild(), seenFree(), beginUpdate()). Throws std::logic_error for a foreign `pending`.
  PlanningUpdateStats finishUpdate(
      PendingUpdate pending,
      const std::function<void(const PlanningUpdateStats&)>& before_end = {});
  /// Re-reads every TSDF block and recomputes the distance field from scratch.
  PlanningUpdateStats rebuild(const BlockOctree& octree);
  /// Forgets the free space seen in `region` (cells whose centre lies in it). The TSDF's own
  /// clearing reaches the layer through update().
  void clearRegion(const MapRegion& region);
  /// Drops planning blocks whose centre lies farther than `max_distance_m` from `point`.
  void dropFartherThan(const Eigen::Vector3d& point_m, double max_distance_m);
  void clear();

  // Readers (thread-safe).
  CellState state(const Eigen::Vector3d& p_world) const;
  /// The TSDF's signed distance at `cell`'s centre as the layer keeps it (quantised; 0 where the
  /// TSDF holds none): what a distance read from the cell as a site is moved by.
  double centreSdfM(const CellIndex& cell) const;
  EsdfSample sample(const Eigen::Vector3d& p_world) const;
  void sampleBatch(const std::vector<Eigen::Vector3d>& points, std::vector<EsdfSample>* out) const;
  /// Calls `fn(cell, state, signed distance m)` for every known cell (unknown cells skipped), in
  /// key order of their blocks.
  void forEachKnownCell(const std::function<void(const CellIndex&, CellState, double)>& fn) const;
  /// Blocks and their seen-free bits, for the map file.
  std::vector<std::pair<BlockKey, PlanningBlock::Bits>> seenFree() const;
  /// Adds seen-free bits (a frame's, a map file's); the next update() or rebuild() gives their new
  /// blocks distances.
  void addSeenFree(const std::vector<std::pair<BlockKey, PlanningBlock::Bits>>& seen_free);

  /// These three never wait for a writer (a status report under the map lock must not wait
  /// for an update running beside the frames): they read sizes each writer leaves behind.
  size_t blockCount() const;
  /// Bytes of the free/occupied bits with their block keys and table entries, and of the ESDF's
  /// per-cell distance and site.
  size_t freeSpaceBytes() const;
  size_t esdfBytes() const;
  /// Frame writes that came while an update ran, added at its end (a counter).
  uint64_t writesKeptForUpdate() const;

 private:
  /// A frame write kept while an update runs: a frame's seen-free cells, or a drop.
  struct DropFarther {
    Eigen::Vector3d point_m;
    double max_distance_m;
  };
  using SeenFree = std::vector<std::pair<BlockKey, PlanningBlock::Bits>>;
  using KeptWrite = std::variant<SeenFree, DropFarther>;
  /// Keeps `write` for the running update's end; false (nothing kept) if none runs.
  bool keepForUpdate(KeptWrite&& write);
  /// Adds the frame writes kept for the running update and lets the next one begin.
  void endUpdate();
  /// Waits until no update runs; the returned lock keeps a new one from beginning.
  std::unique_lock<std::mutex> awaitNoUpdate() const;
  void addSeenFreeLocked(const SeenFree& seen_free);
  /// Publishes blocks_'s size for the readers that do not lock (after every insert or erase).
  void noteSizeLocked();
  void dropFartherThanLocked(const Eigen::Vector3d& point_m, double max_distance_m);
  PlanningBlock* allocate(const BlockKey& key);
  /// How the TSDF's cells are read (TsdfOccupancy).
  TsdfCellParams cellParams() const;
  /// Allocates the transit blocks that `keys` call for where their occupied or free cells
  /// spread past the boxes the rule last acted on; returns how many.
  uint64_t applyTransitRule(std::vector<BlockKey> keys);
  /// Erases `keys` that hold no known cell, then allocates the transit blocks their neighbours
  /// still need (seeded at the next update); returns how many were erased.
  uint64_t eraseUnknownBlocks(std::vector<BlockKey> keys);
  /// The cell's signed distance: to its site's centre, moved onto the surface by the site's
  /// centre_sdf (sub-cell), clamped to [0, max] in magnitude.
  double signedDistance(const BlockKey& key, const PlanningBlock& block, int cell) const;
  EsdfSample sampleLocked(const Eigen::Vector3d& p_world) const;

  PlanningConfig config_;
  PlanningGrid grid_;
  ThreadPool* pool_;
  FreeSpaceRecorder recorder_;
  EsdfPropagator propagator_;
  uint32_t max_dist2_ = 0;
  EsdfTransit transit_;
  mutable std::shared_mutex mutex_;
  PlanningBlockMap blocks_;
  std::atomic<size_t> block_count_{0}, bucket_count_{0};  // blocks_'s, for blockCount() & co.
  /// Since the previous update(): blocks allocated (their cells have no site yet).
  std::vector<BlockKey> fresh_;
  /// Since the previous update(): occupied cells of dropped blocks (flips for the ESDF), and
  /// blocks that may have lost their last known cell (erased at the update if so).
  std::vector<CellIndex> pending_flips_;
  std::vector<BlockKey> maybe_empty_;
  /// Since the previous update(): blocks whose seen-free bits grew their free box (rule_queued).
  std::vector<BlockKey> boxes_grown_;
  std::vector<std::pair<BlockKey, PlanningBlock::Bits>> seen_scratch_;
  /// Whether an update runs (beginUpdate() to finishUpdate()), and the frame writes kept for
  /// its end, in order. Taken before mutex_ when both are held.
  mutable std::mutex update_mutex_;
  mutable std::condition_variable update_done_;
  bool update_running_ = false;         // guarded by update_mutex_
  std::vector<KeptWrite> kept_writes_;  // guarded by update_mutex_
  uint64_t writes_kept_ = 0;            // guarded by update_mutex_
};

/// An update's TSDF reading between beginUpdate() and finishUpdate() (move-only).
class PlanningMap::PendingUpdate {
 public:
  PendingUpdate(PendingUpdate&& other) noexcept
      : map_(std::exchange(other.map_, nullptr)),
        stats(other.stats),
        states(std::move(other.states)) {}
  PendingUpdate& operator=(PendingUpdate&& other) noexcept;
  ~PendingUpdate();

 private:
  friend class PlanningMap;
  PendingUpdate() = default;
  PlanningMap* map_ = nullptr;  // until finishUpdate() takes it
  PlanningUpdateStats stats;
  std::vector<std::vector<TsdfCellState>> states;
};

}  // namespace stereo_fusion
