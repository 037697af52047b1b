#pragma once
#include <atomic>
#include <chrono>
#include <cstdint>

namespace stereo_fusion {

/// What a Mapper is doing now, for a watchdog on another thread.
enum class MapperStage : uint8_t {
  kIdle,
  kValidate,   ///< validateFrame() and the FrameGate
  kLookup,     ///< measurements, coherence, outlier rejection, the block lookup
  kFusion,     ///< the surface update and the new blocks' insertion
  kCarving,    ///< free-space carving
  kEviction,   ///< the memory bound
  kFreeSpace,  ///< recording the space the frame saw empty (planning layer)
  kPlanning,   ///< the planning layer's update
  kMeshing,
  kTexture,
  kClear,  ///< clearRegion()
  kLoad,   ///< adoptMap() and its re-meshing
};
const char* mapperStageName(MapperStage stage);

/// Where a Mapper reports its stage (Mapper::setStageMonitor()): safe to read from any thread.
struct StageMonitor {
  std::atomic<MapperStage> stage{MapperStage::kIdle};
  /// steady_clock ns when the current operation left kIdle (0 while idle).
  std::atomic<int64_t> busy_since_ns{0};

  static int64_t nowNs() {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
               std::chrono::steady_clock::now().time_since_epoch())
        .count();
  }
  /// Seconds the current operation has run; 0 while idle.
  double busySeconds() const {
    const int64_t since = busy_since_ns.load();
    return since == 0 ? 0.0 : 1e-9 * static_cast<double>(nowNs() - since);
  }
};

/// Sets a monitor's stage for a scope and gives the previous one back after (nested operations,
/// e.g. integrate() → updateMesh(), report the inner stage, then the outer again).
class StageScope {
 public:
  StageScope(StageMonitor* monitor, MapperStage stage) : monitor_(monitor) {
    if (!monitor_) return;
    previous_ = monitor_->stage.load();
    if (previous_ == MapperStage::kIdle) monitor_->busy_since_ns = StageMonitor::nowNs();
    monitor_->stage = stage;
  }
  void enter(MapperStage stage) {
    if (monitor_) monitor_->stage = stage;
  }
  ~StageScope() {
    if (!monitor_) return;
    monitor_->stage = previous_;
    if (previous_ == MapperStage::kIdle) monitor_->busy_since_ns = 0;
  }
  StageScope(const StageScope&) = delete;
  StageScope& operator=(const StageScope&) = delete;

 private:
  StageMonitor* monitor_;
  MapperStage previous_ = MapperStage::kIdle;
};

}  // namespace stereo_fusion
