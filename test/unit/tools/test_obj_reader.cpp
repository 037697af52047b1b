// The OBJ/MTL/PNG export of textured meshes read back with the OBJ reader (tools/readers/), and
// the reader's errors. (Texture patches and atlas packing: test/unit/mesh/test_textures.cpp.)

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "MeshTestSupport.h"
#include "TestSupport.h"
#include "readers/ObjReader.h"
#include "stereo_fusion/io/ObjWriter.h"
#include "stereo_fusion/io/TextureAtlas.h"

namespace stereo_fusion::test {
namespace {

namespace fs = std::filesystem;


/// A folder unique to this process and test (ctest runs tests in parallel).
fs::path tempFolder(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("stereo_fusion_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

TEST(ObjExport, TexturedMeshRoundTripsThroughObjMtlAndPng) {
  const sim::AnalyticScene scene = wallScene();
  MapperConfig config = texturedConfig();
  config.texture_border_px = 60;  // leave some blocks untextured: patches and baked colours are exercised
  Mapper mapper(config);
  ASSERT_TRUE(mapper.integrate(renderFrame(scene, vgaCamera(), lookFrom({0, 0, 0}, {0.1, 0, 1.5}))).accepted);
  const fs::path dir = tempFolder("obj_round_trip");
  ObjExportInfo info;
  std::string error;
  ObjExportOptions options;
  options.atlas_edge_px = 512;
  ASSERT_TRUE(writeTexturedObj((dir / "mesh.obj").string(), mapper.mesh().submeshes(), mapper.textures().patches(),
                               options, &info, &error))
      << error;
  EXPECT_EQ(info.textured_blocks, mapper.textures().patches().size());
  ASSERT_GT(info.textured_blocks, 0u);
  ASSERT_GT(info.vertex_colour_blocks, 0u);

  ObjMesh obj;
  ASSERT_TRUE(readObj((dir / "mesh.obj").string(), &obj, &error)) << error;
  size_t vertices = 0, triangles = 0;
  for (const auto& [key, m] : mapper.mesh().submeshes()) {
    vertices += m.positions.size();
    triangles += m.triangles.size();
  }
  EXPECT_EQ(obj.positions.size(), vertices);
  EXPECT_EQ(obj.colors.size(), vertices);
  EXPECT_EQ(obj.normals.size(), vertices);
  EXPECT_EQ(obj.faces.size(), triangles);
  EXPECT_EQ(obj.objects.size(), mapper.mesh().submeshes().size());

  std::vector<cv::Mat> atlases(obj.materials.size());
  for (size_t m = 0; m < obj.materials.size(); ++m) {
    if (obj.materials[m].diffuse_map.empty()) continue;
    cv::Mat bgr = cv::imread(obj.materials[m].diffuse_map, cv::IMREAD_COLOR);
    ASSERT_FALSE(bgr.empty()) << obj.materials[m].diffuse_map;
    cv::cvtColor(bgr, atlases[m], cv::COLOR_BGR2RGB);
  }
  size_t textured_faces = 0, baked_faces = 0;
  double max_colour_error = 0, max_baked_error = 0;
  // Atlas colour at an OBJ texture coordinate (OBJ v points up).
  auto atlas_colour = [&](const cv::Mat& atlas, const Eigen::Vector2f& vt) {
    return sampleBilinear(atlas, Eigen::Vector2f(vt.x(), 1 - vt.y()));
  };
  for (const ObjFace& f : obj.faces) {
    ASSERT_GE(f.object, 0);
    int kx, ky, kz;
    ASSERT_EQ(std::sscanf(obj.objects[f.object].c_str(), "block_%d_%d_%d", &kx, &ky, &kz), 3);
    const BlockKey key{kx, ky, kz};
    const SubMesh& mesh = mapper.mesh().submeshes().at(key);
    const TexturePatch* patch = mapper.textures().find(key);
    ASSERT_GE(f.material, 0);
    const cv::Mat& atlas = atlases[f.material];
    ASSERT_FALSE(atlas.empty()) << "every face has a textured material";
    // The vertex's index inside its block (the OBJ does not weld across blocks).
    std::array<size_t, 3> local;
    for (int k = 0; k < 3; ++k) {
      ASSERT_GE(f.vt[k], 0) << "every face has texture coordinates";
      const Eigen::Vector2f vt = obj.uvs[f.vt[k]];
      ASSERT_TRUE(vt.x() >= 0 && vt.x() <= 1 && vt.y() >= 0 && vt.y() <= 1);
      local[k] = mesh.positions.size();
      for (size_t v = 0; v < mesh.positions.size(); ++v)
        if (mesh.positions[v].isApprox(obj.positions[f.v[k]], 1e-5f)) local[k] = v;
      ASSERT_LT(local[k], mesh.positions.size());
    }
    if (!patch) {
      // Baked vertex colours: each corner shows its vertex colour, the centroid their mean.
      ++baked_faces;
      Eigen::Vector3f mean = Eigen::Vector3f::Zero();
      Eigen::Vector2f centroid = Eigen::Vector2f::Zero();
      for (int k = 0; k < 3; ++k) {
        const auto& c = mesh.colors[local[k]];
        const Eigen::Vector3f colour(c[0], c[1], c[2]);
        mean += colour / 3;
        centroid += obj.uvs[f.vt[k]] / 3;
        max_baked_error = std::max<double>(max_baked_error,
                                           (atlas_colour(atlas, obj.uvs[f.vt[k]]) - colour).cwiseAbs().maxCoeff());
      }
      max_baked_error = std::max<double>(max_baked_error, (atlas_colour(atlas, centroid) - mean).cwiseAbs().maxCoeff());
      continue;
    }
    ++textured_faces;
    // Every triangle of a textured block references its own patch: its atlas and rectangle.
    const AtlasPlacement& placement = info.placements.at(key);
    EXPECT_EQ(obj.materials[f.material].name, "atlas_" + std::to_string(placement.atlas));
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector2f vt = obj.uvs[f.vt[k]];
      const float x = vt.x() * atlas.cols, y = (1 - vt.y()) * atlas.rows;
      EXPECT_GE(x, placement.rect.x - 1e-3);
      EXPECT_LE(x, placement.rect.x + placement.rect.width + 1e-3);
      EXPECT_GE(y, placement.rect.y - 1e-3);
      EXPECT_LE(y, placement.rect.y + placement.rect.height + 1e-3);
      // The atlas shows what the patch showed at that vertex.
      const Eigen::Vector3f expected = sampleBilinear(patch->image_rgb, patch->uvs[local[k]]);
      max_colour_error = std::max<double>(max_colour_error, (atlas_colour(atlas, vt) - expected).cwiseAbs().maxCoeff());
    }
  }
  EXPECT_GT(baked_faces, 0u);
  EXPECT_LT(max_baked_error, 1.5);
  EXPECT_GT(textured_faces, 0u);
  EXPECT_LT(max_colour_error, 1.5);  // same texels; only float rounding of the UVs differs
  // Vertex colours are in the file too, in [0, 1].
  for (size_t i = 0; i < obj.colors.size(); ++i)
    ASSERT_TRUE((obj.colors[i].array() >= 0).all() && (obj.colors[i].array() <= 1).all());
  fs::remove_all(dir);
}

TEST(ObjReader, ReportsBadIndicesWithFileAndLine) {
  const fs::path dir = tempFolder("obj_reader_bad");
  std::ofstream(dir / "bad.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n";
  ObjMesh obj;
  std::string error;
  EXPECT_FALSE(readObj((dir / "bad.obj").string(), &obj, &error));
  EXPECT_NE(error.find("bad.obj:4"), std::string::npos) << error;
  std::ofstream(dir / "quad.obj") << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";
  ASSERT_TRUE(readObj((dir / "quad.obj").string(), &obj, &error)) << error;
  EXPECT_EQ(obj.faces.size(), 2u);
  EXPECT_TRUE(obj.colors.empty());
  fs::remove_all(dir);
}

}  // namespace
}  // namespace stereo_fusion::test
