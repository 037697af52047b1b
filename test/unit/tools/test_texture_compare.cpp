// The texture comparison tool's rasteriser and image metrics, on scenes with known answers.

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <opencv2/core.hpp>

#include "MeshTestSupport.h"
#include "texture_compare/ImageMetrics.h"
#include "texture_compare/MeshRasterizer.h"
#include "texture_compare/ObjRenderable.h"
#include "stereo_fusion/io/ObjWriter.h"

namespace stereo_fusion::test {
namespace {

using SubmeshMap = std::unordered_map<BlockKey, SubMesh, BlockKeyHash>;
using PatchMap = std::unordered_map<BlockKey, TexturePatch, BlockKeyHash>;

/// A quad with corners a, b, c, d (counter-clockwise seen from the camera side) as one submesh.
SubMesh quad(const BlockKey& key, const Eigen::Vector3f& a, const Eigen::Vector3f& b,
             const Eigen::Vector3f& c, const Eigen::Vector3f& d, uint8_t grey) {
  SubMesh m;
  m.key = key;
  m.positions = {a, b, c, d};
  m.normals.assign(4, Eigen::Vector3f(0, 0, -1));
  m.colors.assign(4, {grey, grey, grey});
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

/// A 256 × 4 patch whose red channel is the texel column: red = 256·u − ½ under bilinear sampling.
TexturePatch rampPatch() {
  TexturePatch p;
  p.image_rgb = cv::Mat(4, 256, CV_8UC3);
  for (int x = 0; x < 256; ++x)
    for (int y = 0; y < 4; ++y) p.image_rgb.at<cv::Vec3b>(y, x) = cv::Vec3b(x, 0, 0);
  p.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  return p;
}

TEST(MeshRasterizer, TexturesAreInterpolatedPerspectiveCorrectly) {
  // A quad slanted in depth: x = −1 at z = 1.5 m, x = +1 at z = 3 m. The UV of a pixel is known
  // from the ray–plane intersection; affine (screen-space) interpolation would be off by tens
  // of texels in the middle.
  const StereoCamera camera = qvgaCamera();
  const Eigen::Vector3f a(-1, -1, 1.5), b(1, -1, 3), c(1, 1, 3), d(-1, 1, 1.5);
  SubmeshMap meshes{{BlockKey{0, 0, 0}, quad({0, 0, 0}, a, b, c, d, 100)}};
  PatchMap patches{{BlockKey{0, 0, 0}, rampPatch()}};
  const texcmp::RenderedView view =
      texcmp::renderMesh(meshes, &patches, camera, Eigen::Isometry3d::Identity());
  int checked = 0;
  for (int y = 20; y < camera.height(); y += 37)
    for (int x = 5; x < camera.width(); x += 23) {
      // Ray through pixel centre (x, y) meets the plane z = 2.25 + 0.75·X.
      const double rx = (x - camera.cx()) / camera.fx(), ry = (y - camera.cy()) / camera.fy();
      const double t = 2.25 / (1 - 0.75 * rx);  // depth z along the ray
      const double X = rx * t, Y = ry * t;
      if (std::abs(X) > 0.98 || std::abs(Y) > 0.98) continue;  // stay off the quad's edges
      ASSERT_GT(view.depth_m.at<float>(y, x), 0) << x << "," << y;
      EXPECT_NEAR(view.depth_m.at<float>(y, x), t, 1e-4);
      const double u = (X + 1) / 2;
      const double expected_red = std::clamp(256 * u - 0.5, 0.0, 255.0);
      EXPECT_NEAR(view.rgb.at<cv::Vec3b>(y, x)[0], expected_red, 1.0) << "pixel " << x << "," << y;
      EXPECT_EQ(view.textured.at<uint8_t>(y, x), 255);
      ++checked;
    }
  EXPECT_GT(checked, 20);
}

TEST(MeshRasterizer, NearerSurfaceWinsAndVertexColoursBlend) {
  const StereoCamera camera = qvgaCamera();
  SubmeshMap meshes;
  meshes[{0, 0, 0}] =
      quad({0, 0, 0}, {-2, -2, 3}, {2, -2, 3}, {2, 2, 3}, {-2, 2, 3}, 50);  // far wall
  meshes[{1, 0, 0}] =
      quad({1, 0, 0}, {-0.2f, -0.2f, 1}, {0.2f, -0.2f, 1}, {0.2f, 0.2f, 1}, {-0.2f, 0.2f, 1}, 200);
  // Vertex colours varying along x on the near quad: 0 at x = −0.2, 240 at x = +0.2.
  meshes[{1, 0, 0}].colors = {{0, 0, 0}, {240, 240, 240}, {240, 240, 240}, {0, 0, 0}};
  const texcmp::RenderedView view =
      texcmp::renderMesh(meshes, nullptr, camera, Eigen::Isometry3d::Identity());
  // Image centre (159.5, 119.5) lies between pixels; pixel (160, 120) is at X = 0.5/262.5 m on the
  // near quad.
  const double X = (160 - camera.cx()) / camera.fx();
  EXPECT_NEAR(view.depth_m.at<float>(120, 160), 1.0, 1e-5);
  EXPECT_NEAR(view.rgb.at<cv::Vec3b>(120, 160)[1], 240 * (X + 0.2) / 0.4, 1.0);
  EXPECT_EQ(view.rgb.at<cv::Vec3b>(5, 5)[0], 50);  // the far wall around it
  EXPECT_NEAR(view.depth_m.at<float>(5, 5), 3.0, 1e-5);
  EXPECT_EQ(view.textured.at<uint8_t>(120, 160), 0);
}

TEST(ObjRenderable, TheExportedObjRendersLikeTheTexturedMeshItCameFrom) {
  // End to end: texture patches → OBJ + MTL + atlas PNG → read back → rendered from a new pose.
  sim::AnalyticScene scene;
  scene.add(sim::makePlane({0, 0, 1.5}, {0, 0, -1}), {200, 170, 120});
  Eigen::Isometry3d T_world_box = Eigen::Isometry3d::Identity();
  T_world_box.translation() = Eigen::Vector3d(0.1, 0, 1.2);
  scene.add(sim::makeBox(T_world_box, {0.1, 0.1, 0.1}), {60, 160, 60});
  MapperConfig config;
  config.texture = TextureMode::kPatches;
  config.histogram_min_points = 0;
  Mapper mapper(config);
  const StereoCamera camera = vgaCamera();
  for (double x : {-0.1, 0.0, 0.1})
    ASSERT_TRUE(
        mapper
            .integrate(renderFrame(scene, camera,
                                   sim::lookAt({x, 0, 0}, {0, 0, 1.5}, -Eigen::Vector3d::UnitY())))
            .accepted);
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("stereo_fusion_obj_renderable_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  ObjExportInfo info;
  ObjMesh obj;
  SubmeshMap obj_meshes;
  PatchMap obj_patches;
  std::string error;
  ASSERT_TRUE(writeTexturedObj((dir / "mesh.obj").string(), mapper.mesh().submeshes(),
                               mapper.textures().patches(), {}, &info, &error))
      << error;
  ASSERT_TRUE(readObj((dir / "mesh.obj").string(), &obj, &error)) << error;
  ASSERT_TRUE(texcmp::objToRenderable(obj, &obj_meshes, &obj_patches, &error)) << error;
  std::filesystem::remove_all(dir);
  ASSERT_GT(info.textured_blocks, 10u);
  ASSERT_GT(info.vertex_colour_blocks, 0u);

  const Eigen::Isometry3d view =
      sim::lookAt({0.05, 0.05, 0.1}, {0, 0, 1.5}, -Eigen::Vector3d::UnitY());
  const auto original =
      texcmp::renderMesh(mapper.mesh().submeshes(), &mapper.textures().patches(), camera, view);
  const auto exported = texcmp::renderMesh(obj_meshes, &obj_patches, camera, view);
  const cv::Mat mask = (original.depth_m > 0) & (exported.depth_m > 0);
  ASSERT_GT(cv::countNonZero(mask), 100000);
  EXPECT_GT(cv::countNonZero(exported.textured & mask), cv::countNonZero(mask) * 99 / 100)
      << "every face textured";
  // Same texels through the atlas: equal up to UV rounding; a swapped or unflipped v, a wrong
  // atlas offset or a bad baked tile would drop this far below 40 dB.
  EXPECT_GT(texcmp::squaredError(exported.rgb, original.rgb, mask).psnrDb(), 40.0);
}

TEST(ImageMetrics, PsnrAndGradientEnergyMatchHandWorkedValues) {
  cv::Mat truth(10, 20, CV_8UC3, cv::Scalar(100, 100, 100));
  cv::Mat off = truth + cv::Scalar(5, 5, 5);
  cv::Mat mask(10, 20, CV_8UC1, cv::Scalar(255));
  const texcmp::SquaredError e = texcmp::squaredError(off, truth, mask);
  EXPECT_EQ(e.values, 600u);
  EXPECT_NEAR(e.psnrDb(), 10 * std::log10(255.0 * 255.0 / 25.0), 1e-9);  // 34.15 dB
  EXPECT_TRUE(std::isinf(texcmp::squaredError(truth, truth, mask).psnrDb()));
  // Grey ramp of 2 levels per pixel along x: |∇I|² = 4 everywhere inside the eroded mask.
  cv::Mat ramp(10, 20, CV_8UC3);
  for (int y = 0; y < 10; ++y)
    for (int x = 0; x < 20; ++x) ramp.at<cv::Vec3b>(y, x) = cv::Vec3b(2 * x, 2 * x, 2 * x);
  const texcmp::GradientEnergy g = texcmp::gradientEnergy(ramp, mask);
  EXPECT_EQ(g.pixels, 8u * 18u);  // one pixel eroded on each side
  EXPECT_NEAR(g.mean(), 4.0, 1e-3);
  EXPECT_NEAR(texcmp::gradientEnergy(truth, mask).mean(), 0.0, 1e-9);
}

}  // namespace
}  // namespace stereo_fusion::test
