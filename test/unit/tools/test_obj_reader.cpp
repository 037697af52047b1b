// The OBJ/MTL/PNG export of textured meshes read back with the OBJ reader (tools/readers/), and
// the reader's errors. (Texture patches and atlas packing: test/unit/mesh/test_textures.cpp.)

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
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
  const fs::path dir =
      fs::temp_directory_path() / ("stereo_fusion_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

TEST(ObjExport, TexturedMeshRoundTripsThroughObjMtlAndPng) {
  const sim::AnalyticScene scene = wallScene();
  MapperConfig config = texturedConfig();
  config.texture_border_px =
      60;  // leave some blocks untextured: patches and baked colours are exercised
  Mapper mapper(config);
  ASSERT_TRUE(mapper.integrate(renderFrame(scene, vgaCamera(), lookFrom({0, 0, 0}, {0.1, 0, 1.5})))
                  .accepted);
  const fs::path dir = tempFolder("obj_round_trip");
  ObjExportInfo info;
  std::string error;
  ObjExportOptions options;
  options.atlas_edge_px = 512;
  ASSERT_TRUE(writeTexturedObj((dir / "mesh.obj").string(), mapper.mesh().submeshes(),
                               mapper.textures().patches(), options, &info, &error))
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
        max_baked_error = std::max<double>(
            max_baked_error,
            (atlas_colour(atlas, obj.uvs[f.vt[k]]) - colour).cwiseAbs().maxCoeff());
      }
      max_baked_error = std::max<double>(
          max_baked_error, (atlas_colour(atlas, centroid) - mean).cwiseAbs().maxCoeff());
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
      max_colour_error = std::max<double>(
          max_colour_error, (atlas_colour(atlas, vt) - expected).cwiseAbs().maxCoeff());
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

TEST(ObjReader, ReadsAHandWrittenFileWithEveryElement) {
  // Two objects, a material with a texture, colours on every vertex, UVs, normals, a negative
  // (relative) index, a quad and a comment; the numbers below are read off the file.
  const fs::path dir = tempFolder("obj_reader_hand");
  std::ofstream(dir / "scene.mtl") << "newmtl plain\nKd 1 1 1\nnewmtl wood\nmap_Kd wood.png\n";
  std::ofstream(dir / "scene.obj")
      << "# hand written\nmtllib scene.mtl\n"
         "v 0 0 0 1 0 0\nv 2 0 0 0 1 0\nv 2 1 0.5 0 0 1\nv 0 1 0.5 0.25 0.5 0.75\n"
         "vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\n"
         "o first\nusemtl wood\nf 1/1/1 2/2/1 3/3/1\n"
         "o second\nusemtl plain\nf 1//1 3//1 -1//1\nf 1 2 3 4\n";
  ObjMesh obj;
  std::string error;
  ASSERT_TRUE(readObj((dir / "scene.obj").string(), &obj, &error)) << error;
  ASSERT_EQ(obj.positions.size(), 4u);
  EXPECT_EQ(obj.positions[1], Eigen::Vector3f(2, 0, 0));
  EXPECT_EQ(obj.positions[3], Eigen::Vector3f(0, 1, 0.5f));
  ASSERT_EQ(obj.colors.size(), 4u);
  EXPECT_EQ(obj.colors[3], Eigen::Vector3f(0.25f, 0.5f, 0.75f));
  ASSERT_EQ(obj.uvs.size(), 3u);
  EXPECT_EQ(obj.uvs[2], Eigen::Vector2f(1, 1));
  ASSERT_EQ(obj.normals.size(), 1u);
  EXPECT_EQ(obj.normals[0], Eigen::Vector3f(0, 0, 1));
  ASSERT_EQ(obj.materials.size(), 2u);
  EXPECT_EQ(obj.materials[0].name, "plain");
  EXPECT_TRUE(obj.materials[0].diffuse_map.empty());
  EXPECT_EQ(obj.materials[1].name, "wood");
  EXPECT_EQ(fs::path(obj.materials[1].diffuse_map), dir / "wood.png");
  EXPECT_EQ(obj.objects, (std::vector<std::string>{"first", "second"}));
  // 1 + 1 + the quad's 2 triangles.
  ASSERT_EQ(obj.faces.size(), 4u);
  const ObjFace& first = obj.faces[0];
  EXPECT_EQ(first.v, (std::array<int, 3>{0, 1, 2}));
  EXPECT_EQ(first.vt, (std::array<int, 3>{0, 1, 2}));
  EXPECT_EQ(first.vn, (std::array<int, 3>{0, 0, 0}));
  EXPECT_EQ(obj.materials[first.material].name, "wood");
  EXPECT_EQ(obj.objects[first.object], "first");
  const ObjFace& relative = obj.faces[1];
  EXPECT_EQ(relative.v, (std::array<int, 3>{0, 2, 3}));  // -1 is the last vertex so far
  EXPECT_EQ(relative.vt, (std::array<int, 3>{-1, -1, -1}));
  EXPECT_EQ(obj.materials[relative.material].name, "plain");
  EXPECT_EQ(obj.objects[relative.object], "second");
  // The quad (a 2 × √1.25 rectangle) is two triangles on its four corners covering its area, √5.
  double area = 0.0;
  std::set<int> corners;
  for (size_t f = 2; f < 4; ++f) {
    const ObjFace& face = obj.faces[f];
    EXPECT_EQ(face.vn, (std::array<int, 3>{-1, -1, -1}));
    EXPECT_EQ(obj.objects[face.object], "second");
    corners.insert(face.v.begin(), face.v.end());
    const Eigen::Vector3f& a = obj.positions[face.v[0]];
    area += 0.5 * (obj.positions[face.v[1]] - a).cross(obj.positions[face.v[2]] - a).norm();
  }
  EXPECT_EQ(corners, (std::set<int>{0, 1, 2, 3}));
  EXPECT_NEAR(area, std::sqrt(5.0), 1e-6);
  fs::remove_all(dir);
}

TEST(ObjReader, RefusesBadIndicesUnknownMaterialsAndShortFacesNamingTheFile) {
  const fs::path dir = tempFolder("obj_reader_bad");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"index past the end", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n"},
      {"quad past the end", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 9\n"},
      {"uv past the end", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n"},
      {"unknown material", "v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl nowhere\nf 1 2 3\n"},
      {"two corners", "v 0 0 0\nv 1 0 0\nf 1 2\n"},
  };
  for (const auto& [name, text] : cases) {
    const fs::path path = dir / "bad.obj";
    std::ofstream(path) << text;
    ObjMesh obj;
    std::string error;
    EXPECT_FALSE(readObj(path.string(), &obj, &error)) << name;
    EXPECT_EQ(error.rfind(path.string() + ": ", 0), 0u) << name << ": " << error;
  }
  ObjMesh obj;
  std::string error;
  EXPECT_FALSE(readObj((dir / "missing.obj").string(), &obj, &error));
  EXPECT_NE(error.find("missing.obj"), std::string::npos) << error;
  // Without a colour on every vertex there are no colours (tinyobjloader would fill in white).
  std::ofstream(dir / "plain.obj") << "v 0 0 0\nv 1 0 0 1 0 0\nv 0 1 0\nf 1 2 3\n";
  ASSERT_TRUE(readObj((dir / "plain.obj").string(), &obj, &error)) << error;
  EXPECT_EQ(obj.faces.size(), 1u);
  EXPECT_TRUE(obj.colors.empty());
  fs::remove_all(dir);
}

}  // namespace
}  // namespace stereo_fusion::test
