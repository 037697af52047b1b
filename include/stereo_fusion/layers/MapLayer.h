#pragma once
#include <cstddef>

#include "stereo_fusion/integration/MeasurementImage.h"
#include "stereo_fusion/integration/StereoFrame.h"
#include "stereo_fusion/io/ByteCodec.h"
#include "stereo_fusion/io/MapFile.h"
#include "stereo_fusion/map/BlockChangeLog.h"
#include "stereo_fusion/map/BlockOctree.h"
#include "stereo_fusion/map/MapRegion.h"

namespace stereo_fusion {

/// A fused frame as a layer's per-frame hook sees it, once the map holds it (its new blocks
/// inserted, eviction done).
struct LayerFrame {
  const StereoFrame& frame;
  const MeasurementImage& measurements;  ///< the frame's depths and colours as fusion used them
  uint64_t frames_integrated;            ///< counting this one
};

/// Something kept beside the TSDF and derived from it (the mesh, the planning layer, ...). The
/// map host (Mapper) owns each registered layer, gives it a consumer of the map's change log
/// (the TSDF blocks updated and erased, one entry per block and frame) and calls it:
///  - onFrame() after every fused frame: what a layer must see of the frame itself (its free
///    space, its images) before the next one replaces it;
///  - update() with the block changes since its previous update, at the caller's cadence;
///  - clearRegion() before a clear empties the region's voxels (their changes follow through
///    the log), reset() when the map is dropped;
///  - encode() / adopt() when the map is saved to / replaced by a map file: a layer saves what
///    it cannot derive from the TSDF and rebuilds the rest.
/// Every call comes with the map lock held (MappingSession); the map does not change during one.
class MapLayer {
 public:
  virtual ~MapLayer() = default;
  /// Its change-log consumer's name (diagnostics).
  virtual const char* name() const = 0;
  virtual void onFrame(const LayerFrame& /*frame*/) {}
  virtual void update(const BlockOctree& map, const BlockChangeLog::Changes& changes) = 0;
  /// Re-derives the whole layer from `map` (the same result as its incremental updates).
  virtual void rebuild(const BlockOctree& map) = 0;
  virtual void clearRegion(const MapRegion& /*region*/) {}
  virtual void reset() = 0;
  /// Adds what the map file keeps of this layer to `info` (MapFileInfo's layer sections).
  virtual void encode(MapFileInfo* /*info*/) const {}
  /// The map became `map`, read from a file described by `info`: by default rebuilt from it.
  virtual void adopt(const BlockOctree& map, const MapFileInfo& /*info*/) { rebuild(map); }
  /// Paging and checkpoints: appends to `page` what the layer keeps for the TSDF block `key`
  /// alone (the block's part of its page). A layer that keeps nothing per block writes nothing
  /// and stays whole in memory (the default).
  virtual void savePart(const BlockKey& /*key*/, ByteWriter* /*page*/) const {}
  /// Paging (max_map_memory_mb): the block `key` left memory for the block store, its part
  /// saved (savePart()): the layer drops that part as if the block had never been there —
  /// nothing is reported (the map did not change).
  virtual void pageOut(const BlockKey& /*key*/) {}
  /// The block is back in `map` (at a row of its own): the layer takes back what savePart()
  /// wrote, from `page`; false if it cannot be read (a corrupted store).
  virtual bool pageIn(const BlockOctree& /*map*/, const VoxelBlock& /*block*/,
                      ByteReader* /*page*/) {
    return true;
  }
  /// The map was resumed from its store: `map` holds its blocks, each layer's part came back
  /// through pageIn(); by default the layer is derived again as after a load (adopt()).
  virtual void resumed(const BlockOctree& map, const MapFileInfo& info) { adopt(map, info); }
  /// Whether the host updates the layer itself, inside a frame, when more than
  /// max(kMaxPendingLayerChanges, 4 per block of the map) changes wait for it: true for a
  /// layer whose caller may never update it (its log must not grow without bound); false for
  /// one its caller must update (the mesh: blocksAwaitingMesh()).
  virtual bool catchesUpItself() const { return true; }
};

/// Block changes a layer may leave waiting in the map log (or 4 per block of the map, if more)
/// before the host updates it itself (MapLayer::catchesUpItself()).
constexpr size_t kMaxPendingLayerChanges = 1 << 16;

}  // namespace stereo_fusion
