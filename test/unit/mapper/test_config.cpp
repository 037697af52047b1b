#include <gtest/gtest.h>

#include <algorithm>

#include <yaml-cpp/yaml.h>

#include "stereo_fusion/MapperConfig.h"
#include "stereo_fusion/StageConfigs.h"
#include "stereo_fusion/io/ConfigFile.h"

using namespace stereo_fusion;

namespace {
const std::string kSourceDir = STEREO_FUSION_SOURCE_DIR;
}  // namespace

TEST(Config, DefaultYamlHoldsEveryParameterWithTheCompiledDefault) {
  const YAML::Node yaml = YAML::LoadFile(kSourceDir + "/config/default.yaml");
  const MapperConfig defaults;
  std::vector<std::string> yaml_keys;
  for (const auto& entry : yaml) yaml_keys.push_back(entry.first.as<std::string>());
  std::vector<std::string> spec_keys;
  for (const ParameterSpec& spec : mapperParameterSpecs()) spec_keys.push_back(spec.name);
  EXPECT_EQ(yaml_keys, spec_keys) << "config/default.yaml must list every parameter, in order";
  for (const ParameterSpec& spec : mapperParameterSpecs()) {
    MapperConfig parsed;
    std::string error;
    ASSERT_TRUE(setMapperParameter(&parsed, spec.name, yaml[spec.name].Scalar(), &error)) << error;
    EXPECT_EQ(getMapperParameter(parsed, spec.name), getMapperParameter(defaults, spec.name))
        << spec.name << ": default.yaml and MapperConfig disagree";
  }
}

TEST(Config, DefaultsAreValid) { EXPECT_TRUE(validateMapperConfig(MapperConfig{}).empty()); }

TEST(Config, SetParsesAndRoundTrips) {
  MapperConfig c;
  std::string error;
  EXPECT_TRUE(setMapperParameter(&c, "voxel_size_m", "0.01", &error)) << error;
  EXPECT_DOUBLE_EQ(c.voxel_size_m, 0.01);
  EXPECT_EQ(getMapperParameter(c, "voxel_size_m"), "0.01");
  EXPECT_TRUE(setMapperParameter(&c, "weight_mode", "depth_aware", &error));
  EXPECT_EQ(c.weight_mode, WeightMode::kDepthAware);
  EXPECT_TRUE(setMapperParameter(&c, "lookup_mode", "naive", &error));
  EXPECT_EQ(c.lookup_mode, LookupMode::kNaive);
  EXPECT_TRUE(setMapperParameter(&c, "use_color", "false", &error));
  EXPECT_FALSE(c.use_color);
  EXPECT_TRUE(setMapperParameter(&c, "histogram_min_points", "0", &error));
  EXPECT_EQ(c.histogram_min_points, 0);
  EXPECT_TRUE(setMapperParameter(&c, "scale2_min_depth_m", "1.5", &error));
  EXPECT_DOUBLE_EQ(c.levels.scale2_min_depth_m, 1.5);
}

TEST(Config, RejectsUnknownMalformedAndOutOfRange) {
  MapperConfig c;
  std::string error;
  EXPECT_FALSE(setMapperParameter(&c, "voxel_size", "0.01", &error));
  EXPECT_EQ(error, "unknown parameter 'voxel_size' (did you mean 'voxel_size_m'?)");
  EXPECT_FALSE(setMapperParameter(&c, "voxel_size_m", "abc", &error));
  EXPECT_NE(error.find("voxel_size_m"), std::string::npos) << error;
  EXPECT_FALSE(setMapperParameter(&c, "voxel_size_m", "0.01m", &error));
  EXPECT_FALSE(setMapperParameter(&c, "voxel_size_m", "nan", &error));
  EXPECT_FALSE(setMapperParameter(&c, "voxel_size_m", "0", &error));
  EXPECT_NE(error.find("parameter 'voxel_size_m' = 0 is out of range [0.002, 1] m"),
            std::string::npos)
      << error;
  EXPECT_FALSE(setMapperParameter(&c, "max_depth_m", "0", &error));  // exclusive lower bound
  EXPECT_FALSE(setMapperParameter(&c, "lookup_region_px", "0", &error));
  EXPECT_FALSE(setMapperParameter(&c, "lookup_region_px", "1.5", &error));
  EXPECT_FALSE(setMapperParameter(&c, "weight_mode", "linear", &error));
  EXPECT_NE(error.find("constant | steinbruecker | depth_aware"), std::string::npos) << error;
  EXPECT_FALSE(setMapperParameter(&c, "use_color", "yes please", &error));
  EXPECT_EQ(c.voxel_size_m, MapperConfig{}.voxel_size_m);  // failed sets change nothing
}

TEST(Config, SubnormalAndSpacedValues) {
  MapperConfig c;
  std::string error;
  EXPECT_TRUE(setMapperParameter(&c, "min_depth_m", "1e-310", &error))
      << error;  // subnormal, in range
  EXPECT_NO_THROW(validateMapperConfig(c));
  EXPECT_TRUE(validateMapperConfig(c).empty());
  EXPECT_EQ(getMapperParameter(c, "min_depth_m"), "1e-310");
  EXPECT_FALSE(setMapperParameter(&c, "max_depth_m", " 5", &error));
  EXPECT_FALSE(setMapperParameter(&c, "max_depth_m", "", &error));
  EXPECT_FALSE(setMapperParameter(&c, "truncation_vox", "9", &error));  // capped at 8
}

TEST(Config, CrossParameterRules) {
  MapperConfig c;
  c.weight_falloff_start_vox = 4;
  c.truncation_vox = 4;
  c.levels.scale2_min_depth_m = 5;
  c.levels.scale4_min_depth_m = 3;
  const auto errors = validateMapperConfig(c);
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_NE(errors[0].find("scale2_min_depth_m"), std::string::npos);
  EXPECT_NE(errors[1].find("weight_falloff_start_vox"), std::string::npos);
}

TEST(Config, OccupancyEvidenceMustBeReachable) {
  MapperConfig c;
  c.max_weight = 10;
  c.occupancy_min_weight = 10;
  EXPECT_TRUE(validateMapperConfig(c).empty());
  c.occupancy_min_weight = 10.5;
  const auto errors = validateMapperConfig(c);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("occupancy_min_weight"), std::string::npos);
}

TEST(Config, YamlFileErrorsNameFileLineAndParameter) {
  MapperConfig c;
  std::string error;
  EXPECT_FALSE(
      loadMapperConfigText("voxel_size_m: 0.01\ntruncation_vox: 100\n", "my.yaml", &c, &error));
  EXPECT_NE(error.find("my.yaml:2"), std::string::npos) << error;
  EXPECT_NE(error.find("truncation_vox"), std::string::npos) << error;
  EXPECT_EQ(c.voxel_size_m, MapperConfig{}.voxel_size_m);  // nothing applied on error
  EXPECT_FALSE(loadMapperConfigText("a: [1, 2\n", "broken.yaml", &c, &error));
  EXPECT_NE(error.find("broken.yaml"), std::string::npos) << error;
  EXPECT_FALSE(loadMapperConfigText("voxel_size_m: [1, 2]\n", "list.yaml", &c, &error));
  EXPECT_FALSE(loadMapperConfigText("bogus_key: 3\n", "x.yaml", &c, &error));
  EXPECT_NE(error.find("unknown parameter 'bogus_key'"), std::string::npos) << error;
  EXPECT_FALSE(
      loadMapperConfigText("voxel_size_m: 0.03\ntruncaton_vox: 3\n", "x.yaml", &c, &error));
  EXPECT_EQ(error, "x.yaml:2: unknown parameter 'truncaton_vox' (did you mean 'truncation_vox'?)");
  EXPECT_EQ(c.voxel_size_m, MapperConfig{}.voxel_size_m) << "nothing applied";
  EXPECT_FALSE(loadMapperConfigText("min_depth_m: 9\n", "x.yaml", &c, &error));
  EXPECT_NE(error.find("min_depth_m must be < max_depth_m"), std::string::npos) << error;
  EXPECT_FALSE(loadMapperConfigFile("/nonexistent/file.yaml", &c, &error));
  EXPECT_NE(error.find("cannot open"), std::string::npos);
  EXPECT_TRUE(
      loadMapperConfigText("voxel_size_m: 0.01\nweight_mode: constant\n", "ok.yaml", &c, &error))
      << error;
  EXPECT_DOUBLE_EQ(c.voxel_size_m, 0.01);
  EXPECT_EQ(c.weight_mode, WeightMode::kConstant);
}

// Each stage gets the parameters it uses (its own config), built from MapperConfig in one place
// (stageConfigs()): every field must come from its MapperConfig parameter, and a
// default-constructed one must hold MapperConfig's defaults.
TEST(Config, StageConfigsCarryTheirParameters) {
  MapperConfig c;  // every value differs from its default
  c.voxel_size_m = 0.013;
  c.truncation_vox = 5.5;
  c.lookup_mode = LookupMode::kNaive;
  c.lookup_region_px = 23;
  c.histogram_min_points = 7;
  c.max_lookup_blocks_per_frame = 1234;
  c.weight_mode = WeightMode::kDepthAware;
  c.weight_falloff_start_vox = 1.75;
  c.depth_weight_reference_m = 2.25;
  c.max_weight = 37.0;
  c.update_allocated_finer_level = false;
  c.free_space_carving = false;
  c.free_space_decay = 0.35;
  c.use_color = false;
  c.free_space_window_px = 3;
  const StageConfigs stages = stageConfigs(c);
  const LookupConfig& lookup = stages.pipeline.lookup;
  EXPECT_EQ(lookup.voxel_size_m, 0.013);
  EXPECT_EQ(lookup.truncation_vox, 5.5);
  EXPECT_EQ(lookup.lookup_mode, LookupMode::kNaive);
  EXPECT_EQ(lookup.lookup_region_px, 23);
  EXPECT_EQ(lookup.histogram_min_points, 7);
  EXPECT_EQ(lookup.max_lookup_blocks_per_frame, 1234);
  EXPECT_EQ(lookup.truncationBand().maxM(), c.truncationBand().maxM());
  const FusionConfig& fusion = stages.pipeline.fusion;
  EXPECT_EQ(fusion.voxel_size_m, 0.013);
  EXPECT_EQ(fusion.truncation_vox, 5.5);
  EXPECT_EQ(fusion.weight_mode, WeightMode::kDepthAware);
  EXPECT_EQ(fusion.weight_falloff_start_vox, 1.75);
  EXPECT_EQ(fusion.depth_weight_reference_m, 2.25);
  EXPECT_EQ(fusion.max_weight, 37.0);
  EXPECT_FALSE(fusion.update_allocated_finer_level);
  EXPECT_FALSE(fusion.free_space_carving);
  EXPECT_EQ(fusion.free_space_decay, 0.35);
  EXPECT_FALSE(fusion.use_color);
  const CarveConfig& carve = stages.pipeline.carve;
  EXPECT_EQ(carve.free_space_window_px, 3);
  EXPECT_EQ(carve.fusion.free_space_decay, 0.35);
  EXPECT_EQ(carve.fusion.weight_mode, WeightMode::kDepthAware);
  EXPECT_EQ(carve.fusion.max_weight, 37.0);

  const MapperConfig defaults;
  const MeasurementConfig default_measurement;
  EXPECT_EQ(default_measurement.max_depth_m, defaults.max_depth_m);
  EXPECT_EQ(default_measurement.levels.disparity_noise_px, defaults.disparity_noise_px);
  EXPECT_EQ(default_measurement.levels.level_mode, defaults.level_mode);
  const LookupConfig default_lookup;
  EXPECT_EQ(default_lookup.voxel_size_m, defaults.voxel_size_m);
  EXPECT_EQ(default_lookup.lookup_mode, defaults.lookup_mode);
  EXPECT_EQ(default_lookup.histogram_min_points, defaults.histogram_min_points);
  const CarveConfig default_carve;
  EXPECT_EQ(default_carve.free_space_window_px, defaults.free_space_window_px);
  EXPECT_EQ(default_carve.fusion.free_space_decay, defaults.free_space_decay);
  EXPECT_EQ(default_carve.fusion.weight_mode, defaults.weight_mode);
}

// The stages added to stageConfigs() with the frame pipeline and the layers: measurement,
// level selection, outlier rejection, the contradiction filter, the gate, the pipeline's own
// refusals, eviction, the mesh and the planning layer.
TEST(Config, StageConfigsReachEveryStage) {
  MapperConfig c;  // every value differs from its default
  c.voxel_size_m = 0.03;
  c.min_depth_m = 0.3;
  c.max_depth_m = 6.5;
  c.use_color = false;
  c.level_mode = LevelMode::kDepth;
  c.disparity_noise_px = 0.4;
  c.levels.scale2_min_depth_m = 1.5;
  c.speckle_max_area_px = 40;
  c.speckle_max_diff_px = 2.5;
  c.edge_reject_radius_px = 3;
  c.edge_reject_jump_px = 1.5;
  c.contradiction_filter = false;
  c.contradiction_min_weight = 3.5;
  c.contradiction_sigmas = 2.5;
  c.contradiction_max_share = 0.4;
  c.max_pose_jump_m = 7.0;
  c.max_timestamp_gap_s = 9.0;
  c.require_increasing_timestamps = false;
  c.min_coherent_pixel_share = 0.3;
  c.max_new_blocks_per_frame = 77;
  c.max_blocks = 500;
  c.max_distance_from_camera_m = 12.0;
  c.mesh_enabled = false;
  c.texture = TextureMode::kPatches;
  c.mesh_level_min_coverage = 0.6;
  c.mesh_fill_seams = false;
  c.texture_border_px = 11;
  c.texture_max_patch_px = 48;
  c.planning_enabled = false;
  c.esdf_max_distance_m = 3.0;
  c.occupancy_min_weight = 1.5;
  c.free_space_unmeasured_range_m = 2.0;
  c.max_map_memory_mb = 1.5;
  c.map_store_path = "/var/tmp/pages";
  const StageConfigs s = stageConfigs(c);
  EXPECT_EQ(s.pipeline.block_size_m, 8 * 0.03);
  EXPECT_EQ(s.pipeline.measurement.min_depth_m, 0.3);
  EXPECT_EQ(s.pipeline.measurement.max_depth_m, 6.5);
  EXPECT_FALSE(s.pipeline.measurement.use_color);
  EXPECT_EQ(s.pipeline.measurement.levels.level_mode, LevelMode::kDepth);
  EXPECT_EQ(s.pipeline.measurement.levels.voxel_size_m, 0.03);
  EXPECT_EQ(s.pipeline.measurement.levels.disparity_noise_px, 0.4);
  EXPECT_EQ(s.pipeline.measurement.levels.levels.scale2_min_depth_m, 1.5);
  EXPECT_EQ(s.pipeline.outliers.speckle_max_area_px, 40);
  EXPECT_EQ(s.pipeline.outliers.speckle_max_diff_px, 2.5);
  EXPECT_EQ(s.pipeline.outliers.edge_reject_radius_px, 3);
  EXPECT_EQ(s.pipeline.outliers.edge_reject_jump_px, 1.5);
  EXPECT_FALSE(s.pipeline.contradiction_filter);
  EXPECT_EQ(s.pipeline.contradiction.voxel_size_m, 0.03);
  EXPECT_EQ(s.pipeline.contradiction.contradiction_min_weight, 3.5);
  EXPECT_EQ(s.pipeline.contradiction.contradiction_sigmas, 2.5);
  EXPECT_EQ(s.pipeline.contradiction.contradiction_max_share, 0.4);
  EXPECT_EQ(s.pipeline.disparity_noise_px, 0.4);
  EXPECT_EQ(s.pipeline.gate.max_pose_jump_m, 7.0);
  EXPECT_EQ(s.pipeline.gate.max_timestamp_gap_s, 9.0);
  EXPECT_FALSE(s.pipeline.gate.require_increasing_timestamps);
  EXPECT_EQ(s.pipeline.min_coherent_pixel_share, 0.3);
  EXPECT_EQ(s.pipeline.max_new_blocks_per_frame, 77);
  EXPECT_EQ(s.eviction.max_blocks, 500u);
  EXPECT_EQ(s.eviction.max_distance_from_camera_m, 12.0);
  EXPECT_FALSE(s.mesh.enabled);
  EXPECT_TRUE(s.mesh.textured);
  EXPECT_EQ(s.mesh.meshing.voxel_size_m, 0.03);
  EXPECT_EQ(s.mesh.meshing.level_min_coverage, 0.6);
  EXPECT_FALSE(s.mesh.meshing.fill_faces_from_coarser_levels);
  EXPECT_EQ(s.mesh.texture.border_px, 11);
  EXPECT_EQ(s.mesh.texture.max_patch_px, 48);
  EXPECT_EQ(s.mesh.texture.voxel_size_m, 0.03);
  EXPECT_FALSE(s.planning_enabled);
  // 0.03 · 2 = 6 cm and 0.03 · 4 = 12 cm: 6 cm is nearer 8 cm in ratio (planningCellSizeM()).
  EXPECT_EQ(s.planning.planning.cell_m, c.planningCellSizeM());
  EXPECT_EQ(s.planning.planning.voxels_per_cell, 2);
  EXPECT_EQ(s.planning.planning.max_distance_m, 3.0);
  EXPECT_EQ(s.planning.planning.min_weight, 1.5f);
  EXPECT_EQ(s.planning.planning.unmeasured_range_m, 2.0);
  EXPECT_EQ(s.planning.max_distance_from_camera_m, 12.0);
  EXPECT_EQ(s.paging.max_map_memory_bytes, 1572864u);  // 1.5 · 2^20
  EXPECT_EQ(s.paging.store_path, "/var/tmp/pages");
  EXPECT_EQ(s.paging.voxel_size_m, 0.03);
  // max_depth_m + the widest band: max(truncation_vox, 2) · 4 · voxel.
  EXPECT_EQ(s.paging.max_depth_m, 6.5);
  EXPECT_DOUBLE_EQ(s.paging.band_m, std::max(c.truncation_vox, 2.0) * 4 * 0.03);
  EXPECT_EQ(s.paging.unmeasured_m, 2.0);
}

// The table behind both registries (mapping and node parameters): every type, the messages
// naming parameter, range and unit, failed sets changing nothing, and one definition per name.
TEST(Config, PlanningCellFollowsTheVoxelAndTheRange) {
  MapperConfig c;
  const auto cell = [&](double voxel_m, double max_depth_m, double unmeasured_m = 0.0) {
    c.voxel_size_m = voxel_m;
    c.max_depth_m = max_depth_m;
    c.free_space_unmeasured_range_m = unmeasured_m;
    return c.planningCellSizeM();
  };
  // Indoors (8 m: 8 / 128 = 6.25 cm < 8 cm): the multiple nearest 8 cm in ratio.
  EXPECT_DOUBLE_EQ(cell(0.01, 8.0), 0.08);
  EXPECT_DOUBLE_EQ(cell(0.02, 8.0), 0.08);
  EXPECT_DOUBLE_EQ(cell(0.1, 8.0), 0.1);
  // 25 m: 25 / 128 = 19.5 cm; of 10, 20, 40, 80 cm, 20 cm is nearest in ratio.
  EXPECT_DOUBLE_EQ(cell(0.1, 25.0), 0.2);
  EXPECT_DOUBLE_EQ(cell(0.2, 25.0), 0.2);
  // 40 m at 2 cm: 31.25 cm wanted, the coarsest multiple is 8 · 2 = 16 cm.
  EXPECT_DOUBLE_EQ(cell(0.02, 40.0), 0.16);
  // The unmeasured range carves as far as the measured one: 8 m measured, 25 m unmeasured.
  EXPECT_DOUBLE_EQ(cell(0.1, 8.0, 25.0), 0.2);
  // Given, it is taken as it is.
  c.esdf_voxel_size_m = 0.3;
  EXPECT_DOUBLE_EQ(cell(0.1, 25.0), 0.3);
}

TEST(ParameterTable, ParsesChecksAndNamesEveryType) {
  struct Settings {
    double rate_hz = 2.0;
    int queue = 5;
    bool markers = true;
    std::string frame = "world";
    std::string optional_frame;
    bool keep_oldest = true;
  };
  ParameterTable<Settings> table;
  table.addDouble("rate_hz", "Hz", 0.0, true, 1000.0, "a rate",
                  ParameterTable<Settings>::member(&Settings::rate_hz));
  table.addInt("queue", "frames", 1, 1000, "a queue",
               ParameterTable<Settings>::member(&Settings::queue));
  table.addBool("markers", "markers on", ParameterTable<Settings>::member(&Settings::markers));
  table.addString("frame", false, "a tf frame", "a frame",
                  ParameterTable<Settings>::member(&Settings::frame));
  table.addString("optional_frame", true, "a tf frame, or empty", "another",
                  ParameterTable<Settings>::member(&Settings::optional_frame));
  table.addEnum<bool>("policy", {{"drop_oldest", true}, {"drop_newest", false}}, "which to drop",
                      ParameterTable<Settings>::member(&Settings::keep_oldest));
  ASSERT_EQ(table.specs().size(), 6u);
  EXPECT_EQ(table.specs()[0].range, "[0, 1000]");
  EXPECT_EQ(table.specs()[0].unit, "Hz");
  EXPECT_EQ(table.specs()[3].type, "string");
  EXPECT_EQ(table.specs()[5].range, "drop_oldest | drop_newest");

  Settings s;
  std::string error;
  EXPECT_FALSE(table.set(&s, "queue", "-1", &error));
  EXPECT_EQ(error, "parameter 'queue' = -1 is out of range [1, 1000] frames");
  EXPECT_FALSE(table.set(&s, "queue", "2.5", &error));
  EXPECT_EQ(error, "parameter 'queue': '2.5' is not an integer");
  EXPECT_FALSE(table.set(&s, "rate_hz", "-0.5", &error));
  EXPECT_EQ(error, "parameter 'rate_hz' = -0.5 is out of range [0, 1000] Hz");
  EXPECT_FALSE(table.set(&s, "markers", "maybe", &error));
  EXPECT_EQ(error, "parameter 'markers': 'maybe' is not true or false");
  EXPECT_FALSE(table.set(&s, "frame", "", &error));
  EXPECT_EQ(error, "parameter 'frame' must not be empty (a tf frame)");
  EXPECT_FALSE(table.set(&s, "policy", "drop_all", &error));
  EXPECT_EQ(error, "parameter 'policy': 'drop_all' is not one of drop_oldest | drop_newest");
  EXPECT_FALSE(table.set(&s, "nonsense", "1", &error));
  EXPECT_EQ(error, "unknown parameter 'nonsense' (did you mean 'queue'?)");
  EXPECT_FALSE(table.set(&s, "rate_h", "1", &error));
  EXPECT_EQ(error, "unknown parameter 'rate_h' (did you mean 'rate_hz'?)");
  EXPECT_EQ(s.queue, 5);
  EXPECT_EQ(s.frame, "world");
  EXPECT_TRUE(s.keep_oldest);

  EXPECT_TRUE(table.set(&s, "queue", "7", &error)) << error;
  EXPECT_TRUE(table.set(&s, "rate_hz", "0.25", &error)) << error;
  EXPECT_TRUE(table.set(&s, "markers", "0", &error)) << error;
  EXPECT_TRUE(table.set(&s, "frame", "map", &error)) << error;
  EXPECT_TRUE(table.set(&s, "optional_frame", "", &error)) << error;
  EXPECT_TRUE(table.set(&s, "policy", "drop_newest", &error)) << error;
  EXPECT_EQ(s.queue, 7);
  EXPECT_EQ(s.rate_hz, 0.25);
  EXPECT_FALSE(s.markers);
  EXPECT_EQ(s.frame, "map");
  EXPECT_FALSE(s.keep_oldest);
  EXPECT_EQ(table.get(s, "policy"), "drop_newest");
  EXPECT_EQ(table.get(s, "rate_hz"), "0.25");
  EXPECT_EQ(table.get(s, "markers"), "false");
  EXPECT_EQ(table.get(s, "nonsense"), "");

  EXPECT_TRUE(table.rangeErrors(s).empty());
  s.queue = 0;
  s.frame.clear();
  const std::vector<std::string> errors = table.rangeErrors(s);
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_EQ(errors[0], "parameter 'queue' = 0 is out of range [1, 1000] frames");
  EXPECT_EQ(errors[1], "parameter 'frame' must not be empty (a tf frame)");

  EXPECT_THROW(
      table.addInt("queue", "", 0, 1, "again", ParameterTable<Settings>::member(&Settings::queue)),
      std::logic_error);
}

// An unknown name is answered with the nearest known one: Levenshtein distance (insertions,
// deletions, substitutions), the first of equally near names.
TEST(ParameterTable, UnknownNamesNameTheNearestKnownName) {
  using namespace parameter_text;
  EXPECT_EQ(editDistance("", ""), 0u);
  EXPECT_EQ(editDistance("abc", ""), 3u);
  EXPECT_EQ(editDistance("", "ab"), 2u);
  EXPECT_EQ(editDistance("kitten", "sitting"), 3u);
  EXPECT_EQ(editDistance("tf_timout_s", "tf_timeout_s"), 1u);
  EXPECT_EQ(editDistance("flaw", "lawn"), 2u);
  const std::vector<std::string> known{"tf_timeout_s", "queue_size", "world_frame", "queue_policy"};
  EXPECT_EQ(nearestName("tf_timout_s", known), "tf_timeout_s");
  EXPECT_EQ(nearestName("queue_sizes", known), "queue_size");
  EXPECT_EQ(nearestName("worldframe", known), "world_frame");
  EXPECT_EQ(nearestName("x", {}), "");
  EXPECT_EQ(nearestName("ab", {"xb", "ay"}), "xb") << "the first of equally near names";
  EXPECT_EQ(unknownParameterMessage("/stereo_fusion/queue_lenght", "queue_lenght", known),
            "unknown parameter '/stereo_fusion/queue_lenght' (did you mean 'queue_size'?)");
  EXPECT_EQ(unknownParameterMessage("x", "x", {}), "unknown parameter 'x'");
}
