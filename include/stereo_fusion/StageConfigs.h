#pragma once
#include "stereo_fusion/MapperConfig.h"
#include "stereo_fusion/integration/FramePipeline.h"
#include "stereo_fusion/layers/MeshLayer.h"
#include "stereo_fusion/layers/PlanningLayer.h"
#include "stereo_fusion/map/EvictionPolicy.h"
#include "stereo_fusion/paging/PagingConfig.h"

namespace stereo_fusion {

/// What every stage and layer reads, each its own config, taken from the parameter table
/// (MapperConfig) here and nowhere else: a stage never sees a parameter it does not use, and
/// a new parameter reaches its stage through exactly one line of stageConfigs().
struct StageConfigs {
  FramePipelineConfig pipeline;  ///< the frame's stages, measurement to carving
  EvictionLimits eviction;       ///< the map host's memory bound
  MeshLayerConfig mesh;
  bool planning_enabled = MapperConfig{}.planning_enabled;
  PlanningLayerConfig planning;
  PagingConfig paging;  ///< the map host's pages beyond max_map_memory_mb
};

/// Every stage's config from a (validated) MapperConfig.
StageConfigs stageConfigs(const MapperConfig& config);

}  // namespace stereo_fusion
