// Texture patches per submesh (thesis §3.6 method B): view choice, UVs, occlusion, memory cap,
// atlas packing and the OBJ export's argument check (the OBJ/MTL/PNG export read back:
// test/unit/tools/test_obj_reader.cpp).

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <random>

#include "MeshTestSupport.h"
#include "TestSupport.h"
#include "stereo_fusion/io/ObjWriter.h"
#include "stereo_fusion/io/TextureAtlas.h"

namespace stereo_fusion::test {
namespace {

TEST(TextureStore, PatchesCoverTheirSubmeshWithUvsInTheUnitSquareAndTrueColours) {
  const sim::AnalyticScene scene = wallScene();
  const StereoCamera camera = vgaCamera();
  const Eigen::Isometry3d pose = lookFrom({0, 0, 0}, {0.1, 0, 1.5});
  MapperConfig config = texturedConfig();
  config.texture_max_patch_px = 128;  // no downscaling at this distance: texels = image pixels
  Mapper mapper(config);
  const IntegrationResult r = mapper.integrate(renderFrame(scene, camera, pose));
  ASSERT_TRUE(r.accepted);
  const auto& patches = mapper.textures().patches();
  ASSERT_GT(patches.size(), 50u);
  EXPECT_EQ(r.texture.retextured, patches.size());

  const Eigen::Isometry3d T_camera_world = pose.inverse();
  size_t fully_inside = 0;
  double colour_error_sum = 0;
  size_t samples = 0;
  for (const auto& [key, mesh] : mapper.mesh().submeshes()) {
    bool inside = true;
    for (const auto& p : mesh.positions) {
      Eigen::Vector2d uv;
      inside = inside && camera.project(T_camera_world * p.cast<double>(), &uv) &&
               camera.isInImage(uv, config.texture_border_px);
    }
    fully_inside += inside;
    const TexturePatch* patch = mapper.textures().find(key);
    // A block is textured exactly when the frame sees all of it inside the 24 px border.
    EXPECT_EQ(patch != nullptr, inside) << key;
    if (!patch) continue;
    ASSERT_EQ(patch->uvs.size(), mesh.positions.size()) << key;
    EXPECT_EQ(patch->frame_index, 1u);
    EXPECT_LE(patch->image_rgb.cols, config.texture_max_patch_px);
    EXPECT_LE(patch->image_rgb.rows, config.texture_max_patch_px);
    for (size_t v = 0; v < mesh.positions.size(); ++v) {
      const Eigen::Vector2f& uv = patch->uvs[v];
      ASSERT_TRUE(uv.x() >= 0 && uv.x() <= 1 && uv.y() >= 0 && uv.y() <= 1)
          << key << " uv " << uv.transpose();
      // The patch at the vertex's UV shows the scene at the vertex.
      const Eigen::Vector3f seen = sampleBilinear(patch->image_rgb, uv);
      const Eigen::Vector3d truth = scene.colorAt(mesh.positions[v].cast<double>(), 0);
      colour_error_sum += (seen.cast<double>() - truth).cwiseAbs().mean();
      ++samples;
    }
  }
  EXPECT_EQ(fully_inside, patches.size());
  ASSERT_GT(samples, 0u);
  // Bilinear sampling of a point-sampled texture with ~7 px features: a few levels of error.
  // (A UV off by a whole texel or a flipped axis gives well over 20.)
  EXPECT_LT(colour_error_sum / samples, 8.0);
}

TEST(TextureStore, PatchEdgeIsCappedAndUvsStillPointAtTheSameSurface) {
  const sim::AnalyticScene scene = wallScene();
  const Eigen::Isometry3d pose = lookFrom({0, 0, 0.9}, {0, 0, 1.5});  // 0.6 m: blocks span ~140 px
  MapperConfig config = texturedConfig();
  config.texture_max_patch_px = 24;
  Mapper mapper(config);
  ASSERT_TRUE(mapper.integrate(renderFrame(scene, vgaCamera(), pose)).accepted);
  ASSERT_GT(mapper.textures().patches().size(), 4u);
  size_t image_bytes = 0, downscaled = 0;
  for (const auto& [key, patch] : mapper.textures().patches()) {
    EXPECT_LE(patch.image_rgb.cols, 24);
    EXPECT_LE(patch.image_rgb.rows, 24);
    downscaled += patch.crop_size_px.maxCoeff() > 24;
    image_bytes += patch.image_rgb.total() * 3;
  }
  EXPECT_GT(downscaled, 0u);
  EXPECT_LE(image_bytes, mapper.textures().patches().size() * 3 * 24 * 24);
  EXPECT_GE(mapper.textures().memoryBytes(), image_bytes);
}

TEST(TextureStore, OffByDefaultAndNothingIsStored) {
  Mapper mapper(MapperConfig{});
  EXPECT_EQ(MapperConfig{}.texture, TextureMode::kOff);
  ASSERT_TRUE(
      mapper.integrate(renderFrame(wallScene(), vgaCamera(), lookFrom({0, 0, 0}, {0, 0, 1.5})))
          .accepted);
  EXPECT_GT(mapper.mesh().submeshes().size(), 0u);
  EXPECT_TRUE(mapper.textures().patches().empty());
}

TEST(TextureStore, PatchesNeedIncrementalMeshing) {
  MapperConfig config = texturedConfig();
  config.mesh_enabled = false;
  const std::vector<std::string> errors = validateMapperConfig(config);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("mesh_enabled"), std::string::npos);
  EXPECT_THROW(Mapper{config}, std::invalid_argument);
}

TEST(TextureStore, HiddenVerticesNeverTakeTheOccludersColour) {
  // A blue wall at z = 2 m and a red box in front of it. Two oblique views see the wall behind
  // the box; the last view is closer and frontal (it scores higher) but the box hides part of
  // the wall from it.
  sim::AnalyticScene scene;
  scene.add(sim::makePlane({0, 0, 2.0}, {0, 0, -1}), {40, 60, 220});
  Eigen::Isometry3d T_world_box = Eigen::Isometry3d::Identity();
  T_world_box.translation() = Eigen::Vector3d(0, 0, 1.3);
  scene.add(sim::makeBox(T_world_box, {0.15, 0.15, 0.15}), {230, 40, 30});
  const StereoCamera camera = vgaCamera();
  const Eigen::Vector3d eye_front(0, 0, 0.6);
  const std::vector<Eigen::Isometry3d> poses = {lookFrom({-0.9, 0, 0.2}, {0, 0, 2}),
                                                lookFrom({0.9, 0, 0.2}, {0, 0, 2}),
                                                lookFrom(eye_front, {0, 0, 2})};
  Mapper mapper(texturedConfig());
  IntegrationResult last;
  for (const auto& pose : poses) {
    last = mapper.integrate(renderFrame(scene, camera, pose));
    ASSERT_TRUE(last.accepted);
  }
  EXPECT_GT(last.texture.occluded, 0u) << "the front view must have met hidden vertices";
  EXPECT_GT(last.texture.retextured, 0u);

  size_t wall_vertices = 0, hidden_from_front = 0, front_patches = 0;
  for (const auto& [key, patch] : mapper.textures().patches()) {
    const SubMesh& mesh = mapper.mesh().submeshes().at(key);
    bool wall_only = true;
    for (const auto& p : mesh.positions) wall_only = wall_only && p.z() > 1.9;
    if (!wall_only) continue;
    front_patches += patch.frame_index == 3;
    for (size_t v = 0; v < mesh.positions.size(); ++v) {
      const Eigen::Vector3d p = mesh.positions[v].cast<double>();
      const Eigen::Vector3f c = sampleBilinear(patch.image_rgb, patch.uvs[v]);
      ++wall_vertices;
      const sim::Hit hit = scene.raycast(eye_front, (p - eye_front).normalized());
      hidden_from_front += hit.primitive == 1;
      ASSERT_GT(c.z(), c.x()) << "wall vertex " << p.transpose() << " of block " << key
                              << " textured from frame " << patch.frame_index
                              << " shows the red box";
    }
  }
  EXPECT_GT(wall_vertices, 500u);
  EXPECT_GT(front_patches, 0u) << "the front view wins where it sees the whole block";
  EXPECT_GT(hidden_from_front, 20u)
      << "wall behind the box must be textured from the oblique views";
}

TEST(TextureStore, RebuildReprojectsThePatchesOntoTheNewSubmeshes) {
  Mapper mapper(texturedConfig());
  ASSERT_TRUE(
      mapper.integrate(renderFrame(wallScene(), vgaCamera(), lookFrom({0, 0, 0}, {0, 0, 1.5})))
          .accepted);
  const size_t before = mapper.textures().patches().size();
  ASSERT_GT(before, 0u);
  mapper.rebuildMesh();
  EXPECT_EQ(mapper.textures().patches().size(), before);  // same geometry: every patch still fits
  for (const auto& [key, patch] : mapper.textures().patches())
    EXPECT_EQ(patch.uvs.size(), mapper.mesh().submeshes().at(key).positions.size());
}

TEST(TextureAtlas, ShelfPackingKeepsPatchesAndGuttersDisjointAndInside) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> edge(1, 64);
  std::vector<cv::Size> sizes;
  std::vector<cv::Mat> patches;
  for (int i = 0; i < 300; ++i) {
    sizes.emplace_back(edge(rng), edge(rng));
    patches.emplace_back(sizes.back(), CV_8UC3);
    cv::randu(patches.back(), cv::Scalar::all(0), cv::Scalar::all(256));
  }
  const int gutter = 2, atlas_edge = 256;
  const AtlasLayout layout = packAtlas(sizes, atlas_edge, gutter);
  ASSERT_EQ(layout.placements.size(), sizes.size());
  ASSERT_GT(layout.atlas_sizes.size(), 1u) << "300 patches cannot fit one 256² atlas";
  for (size_t i = 0; i < sizes.size(); ++i) {
    const AtlasPlacement& p = layout.placements[i];
    ASSERT_GE(p.atlas, 0);
    ASSERT_LT(p.atlas, static_cast<int>(layout.atlas_sizes.size()));
    EXPECT_EQ(p.rect.size(), sizes[i]);
    const cv::Rect framed(p.rect.x - gutter, p.rect.y - gutter, p.rect.width + 2 * gutter,
                          p.rect.height + 2 * gutter);
    const cv::Size atlas = layout.atlas_sizes[p.atlas];
    EXPECT_TRUE((framed & cv::Rect(0, 0, atlas.width, atlas.height)) == framed) << i;
    for (size_t j = 0; j < i; ++j) {
      const AtlasPlacement& q = layout.placements[j];
      if (q.atlas != p.atlas) continue;
      const cv::Rect other(q.rect.x - gutter, q.rect.y - gutter, q.rect.width + 2 * gutter,
                           q.rect.height + 2 * gutter);
      ASSERT_EQ((framed & other).area(), 0) << "patches " << i << " and " << j << " overlap";
    }
  }
  const std::vector<cv::Mat> atlases = renderAtlases(layout, patches, gutter);
  for (size_t i = 0; i < sizes.size(); ++i) {
    const AtlasPlacement& p = layout.placements[i];
    EXPECT_EQ(cv::norm(atlases[p.atlas](p.rect), patches[i], cv::NORM_INF), 0.0) << i;
    // The gutter replicates the border: the texel left of the top-left corner repeats it.
    EXPECT_EQ(atlases[p.atlas].at<cv::Vec3b>(p.rect.y, p.rect.x - 1),
              patches[i].at<cv::Vec3b>(0, 0));
  }
  EXPECT_THROW(packAtlas({cv::Size(255, 10)}, atlas_edge, gutter), std::invalid_argument);
}

TEST(ObjExport, RefusesAPathThatIsNotObj) {
  ObjExportInfo info;
  std::string error;
  EXPECT_FALSE(writeTexturedObj("/tmp/x.ply", {}, {}, {}, &info, &error));
  EXPECT_NE(error.find(".obj"), std::string::npos);
}

}  // namespace
}  // namespace stereo_fusion::test
