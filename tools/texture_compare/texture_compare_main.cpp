// stereo_fusion_texture_compare: fuses the even frames of a simulated sequence with texture
// patches on, renders the vertex-coloured and the textured mesh into the held-out odd frames'
// poses and compares both with the simulator's ground-truth colour images (PSNR, sharpness).
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "cli/CommandLine.h"
#include "cli/NumberChecks.h"
#include "fuser/FuseArguments.h"
#include "readers/DatasetReader.h"
#include "readers/ObjReader.h"
#include "stereo_fusion/Mapper.h"
#include "stereo_fusion/io/ObjWriter.h"
#include "texture_compare/ImageMetrics.h"
#include "texture_compare/MeshRasterizer.h"
#include "texture_compare/ObjRenderable.h"

namespace {

namespace fs = std::filesystem;
using namespace stereo_fusion;

cv::Mat toRgb(const cv::Mat& colour) {
  if (colour.channels() == 3) return colour;
  cv::Mat rgb;
  cv::cvtColor(colour, rgb, cv::COLOR_GRAY2RGB);
  return rgb;
}

/// Panels side by side, each under a caption bar; `scale` > 1 magnifies with nearest neighbour.
cv::Mat sideBySide(const std::vector<cv::Mat>& panels, const std::vector<std::string>& captions,
                   double scale) {
  const int bar = 26;
  std::vector<cv::Mat> columns;
  for (size_t i = 0; i < panels.size(); ++i) {
    cv::Mat big;
    cv::resize(panels[i], big, cv::Size(), scale, scale,
               scale >= 1 ? cv::INTER_NEAREST : cv::INTER_AREA);
    cv::Mat column(big.rows + bar, big.cols, CV_8UC3, cv::Scalar(255, 255, 255));
    big.copyTo(column(cv::Rect(0, bar, big.cols, big.rows)));
    cv::putText(column, captions[i], cv::Point(6, 18), cv::FONT_HERSHEY_SIMPLEX, 0.5,
                cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    if (i + 1 < panels.size())
      cv::copyMakeBorder(column, column, 0, 0, 0, 4, cv::BORDER_CONSTANT,
                         cv::Scalar(255, 255, 255));
    columns.push_back(column);
  }
  cv::Mat out;
  cv::hconcat(columns, out);
  return out;
}

bool writeRgbPng(const fs::path& path, const cv::Mat& rgb) {
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  return cv::imwrite(path.string(), bgr, {cv::IMWRITE_PNG_COMPRESSION, 9});
}

char buffer[256];
std::string format(const char* fmt, double a, double b = 0) {
  std::snprintf(buffer, sizeof(buffer), fmt, a, b);
  return buffer;
}

/// The command line: what to fuse and compare, and how many views.
struct CompareOptions {
  std::string sequence, out_dir;
  cli::MapperConfigArguments config_arguments;
  FuseOptions fuse;       ///< its config, from --config and --set as the fuser reads them
  size_t views = 0;       ///< 0: every held-out frame
  long figure_view = -1;  ///< < 0: the middle one
};

void addCompareArguments(CLI::App* app, CompareOptions* o) {
  app->description(
      "Fuses the even frames of a dataset folder with texture=patches, renders the\n"
      "vertex-coloured and the textured mesh into the poses of the odd (held-out) frames and\n"
      "compares both with those frames' colour images (for simulated sequences: the exact\n"
      "ground truth). The textured mesh is also exported as OBJ + MTL + atlas, read back and\n"
      "rendered, to check the export. Prints and writes <out-dir>/texture_compare.json and the\n"
      "figures <out-dir>/texture_compare_full.png and texture_compare_zoom.png (ground truth |\n"
      "vertex colour | texture).");
  app->footer("Exit codes: 0 done, 1 unreadable input or nothing to compare, 2 bad arguments.");
  app->add_option("seq-folder", o->sequence, "the dataset folder")->required();
  app->add_option("out-dir", o->out_dir, "where the JSON and the figures go")->required();
  cli::addMapperConfigArguments(app, &o->config_arguments);
  app->add_option("--views", o->views,
                  "evaluate N held-out frames spread over the sequence (default: all)")
      ->check(cli::nonNegativeNumber());
  app->add_option("--figure-view", o->figure_view,
                  "which evaluated view the figures show (default: the middle one)")
      ->check(cli::nonNegativeNumber());
  app->callback([o] {
    std::string error;
    if (!applyFuseParameters(o->config_arguments, false, &o->fuse, &error))
      throw CLI::ValidationError(error);
  });
}

/// The comparison (see the top of the file); returns the exit code.
int compareTextures(CompareOptions options) {
  const size_t views = options.views;
  long figure_view = options.figure_view;  // then the index of the view the figures show
  std::string error;
  options.fuse.config.texture = TextureMode::kPatches;
  auto reader = DatasetReader::open(options.sequence, &error);
  if (!reader) {
    std::fprintf(stderr, "error: %s\n", error.c_str());
    return 1;
  }
  fs::create_directories(options.out_dir);

  // Fuse the even frames.
  Mapper mapper(options.fuse.config);
  size_t fused = 0;
  for (size_t i = 0; i < reader->size(); i += 2) {
    StereoFrame frame;
    if (!reader->load(i, &frame, &error)) {
      std::fprintf(stderr, "skipping frame %zu: %s\n", i, error.c_str());
      continue;
    }
    fused += mapper.integrate(frame).accepted;
  }
  const auto& submeshes = mapper.mesh().submeshes();
  const auto& patches = mapper.textures().patches();
  std::printf(
      "fused %zu even frames: %zu submeshes, %zu with a texture patch, texture memory %.2f MB "
      "(cap %d px per patch edge)\n",
      fused, submeshes.size(), patches.size(), mapper.textures().memoryBytes() / 1048576.0,
      options.fuse.config.texture_max_patch_px);

  // The export, read back: what a viewer loading mesh.obj gets.
  const fs::path obj_dir =
      fs::temp_directory_path() / ("stereo_fusion_texture_compare_" + std::to_string(getpid()));
  fs::create_directories(obj_dir);
  ObjExportInfo export_info;
  ObjMesh obj;
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> obj_meshes;
  std::unordered_map<BlockKey, TexturePatch, BlockKeyHash> obj_patches;
  const bool obj_ok = writeTexturedObj((obj_dir / "mesh.obj").string(), submeshes, patches,
                                       ObjExportOptions{}, &export_info, &error) &&
                      readObj((obj_dir / "mesh.obj").string(), &obj, &error) &&
                      texcmp::objToRenderable(obj, &obj_meshes, &obj_patches, &error);
  fs::remove_all(obj_dir);
  if (!obj_ok) {
    std::fprintf(stderr, "error: OBJ export round trip: %s\n", error.c_str());
    return 1;
  }

  // Held-out odd frames, spread evenly when fewer are asked for.
  std::vector<size_t> held_out;
  for (size_t i = 1; i < reader->size(); i += 2) held_out.push_back(i);
  if (views > 0 && views < held_out.size()) {
    std::vector<size_t> chosen;
    for (size_t k = 0; k < views; ++k) chosen.push_back(held_out[k * held_out.size() / views]);
    held_out = chosen;
  }
  if (figure_view < 0 || figure_view >= static_cast<long>(held_out.size()))
    figure_view = held_out.size() / 2;

  texcmp::SquaredError err_vertex, err_texture, err_obj;
  texcmp::GradientEnergy ge_vertex, ge_texture, ge_truth;
  size_t covered = 0, textured_px = 0;
  nlohmann::ordered_json per_view = nlohmann::ordered_json::array();
  std::printf("%6s %10s %12s %12s %12s %10s %10s %10s\n", "frame", "covered", "PSNR vertex",
              "PSNR texture", "PSNR OBJ", "GE vertex", "GE texture", "GE truth");
  for (size_t k = 0; k < held_out.size(); ++k) {
    StereoFrame frame;
    if (!reader->load(held_out[k], &frame, &error) || frame.color.empty()) {
      std::fprintf(stderr, "skipping held-out frame %zu: %s\n", held_out[k], error.c_str());
      continue;
    }
    const cv::Mat truth = toRgb(frame.color);
    const texcmp::RenderedView vertex =
        texcmp::renderMesh(submeshes, nullptr, frame.camera, frame.T_world_camera);
    const texcmp::RenderedView texture =
        texcmp::renderMesh(submeshes, &patches, frame.camera, frame.T_world_camera);
    const texcmp::RenderedView exported =
        texcmp::renderMesh(obj_meshes, &obj_patches, frame.camera, frame.T_world_camera);
    // The renders share the geometry, so they cover the same pixels (up to ties on edges the
    // unwelded OBJ may resolve differently).
    const cv::Mat mask = vertex.depth_m > 0;
    const auto ev = texcmp::squaredError(vertex.rgb, truth, mask);
    const auto et = texcmp::squaredError(texture.rgb, truth, mask);
    const auto eo = texcmp::squaredError(exported.rgb, truth, mask);
    err_obj.sum += eo.sum, err_obj.values += eo.values;
    const auto gv = texcmp::gradientEnergy(vertex.rgb, mask);
    const auto gt = texcmp::gradientEnergy(texture.rgb, mask);
    const auto gg = texcmp::gradientEnergy(truth, mask);
    err_vertex.sum += ev.sum, err_vertex.values += ev.values;
    err_texture.sum += et.sum, err_texture.values += et.values;
    ge_vertex.sum += gv.sum, ge_vertex.pixels += gv.pixels;
    ge_texture.sum += gt.sum, ge_texture.pixels += gt.pixels;
    ge_truth.sum += gg.sum, ge_truth.pixels += gg.pixels;
    const size_t n = static_cast<size_t>(cv::countNonZero(mask));
    covered += n;
    textured_px += static_cast<size_t>(cv::countNonZero(texture.textured));
    const double share = n / static_cast<double>(mask.total());
    std::printf("%6zu %9.1f%% %9.2f dB %9.2f dB %9.2f dB %10.1f %10.1f %10.1f\n", held_out[k],
                100 * share, ev.psnrDb(), et.psnrDb(), eo.psnrDb(), gv.mean(), gt.mean(),
                gg.mean());
    per_view.push_back({{"frame", held_out[k]},
                        {"covered_share", share},
                        {"psnr_vertex_db", ev.psnrDb()},
                        {"psnr_texture_db", et.psnrDb()},
                        {"psnr_exported_obj_db", eo.psnrDb()},
                        {"gradient_energy_vertex", gv.mean()},
                        {"gradient_energy_texture", gt.mean()},
                        {"gradient_energy_truth", gg.mean()}});
    if (static_cast<long>(k) == figure_view) {
      const std::vector<cv::Mat> full = {truth, vertex.rgb, texture.rgb};
      const std::vector<std::string> captions = {
          "ground truth (frame " + std::to_string(held_out[k]) + ", held out)",
          format("vertex colour  PSNR %.1f dB", ev.psnrDb()),
          format("texture patches  PSNR %.1f dB", et.psnrDb())};
      bool ok = writeRgbPng(fs::path(options.out_dir) / "texture_compare_full.png",
                            sideBySide(full, captions, 0.5));
      // A quarter of the width and height around the image centre, magnified 2× (nearest).
      const cv::Rect centre(truth.cols / 4 + truth.cols / 8, truth.rows / 4 + truth.rows / 8,
                            truth.cols / 4, truth.rows / 4);
      ok &= writeRgbPng(
          fs::path(options.out_dir) / "texture_compare_zoom.png",
          sideBySide({truth(centre), vertex.rgb(centre), texture.rgb(centre)},
                     {"ground truth (centre, 2x)", "vertex colour", "texture patches"}, 2.0));
      if (!ok) {
        std::fprintf(stderr, "error: cannot write the figures to %s\n", options.out_dir.c_str());
        return 1;
      }
    }
  }
  if (err_vertex.values == 0) {
    std::fprintf(stderr, "error: no held-out frame was covered by the mesh\n");
    return 1;
  }
  std::printf(
      "all %zu views: PSNR vertex colour %.2f dB, texture patches %.2f dB; gradient energy vertex "
      "%.1f, "
      "texture %.1f, ground truth %.1f; %.1f %% of covered pixels drawn from a patch\n"
      "exported mesh.obj read back and rendered: PSNR %.2f dB (%zu textured + %zu baked "
      "vertex-colour blocks)\n",
      held_out.size(), err_vertex.psnrDb(), err_texture.psnrDb(), ge_vertex.mean(),
      ge_texture.mean(), ge_truth.mean(), 100.0 * textured_px / covered, err_obj.psnrDb(),
      export_info.textured_blocks, export_info.vertex_colour_blocks);
  nlohmann::ordered_json j;
  j["sequence"] = options.sequence;
  j["fused_frames"] = fused;
  j["held_out_views"] = held_out.size();
  j["submeshes"] = submeshes.size();
  j["textured_submeshes"] = patches.size();
  j["texture_bytes"] = mapper.textures().memoryBytes();
  j["texture_max_patch_px"] = options.fuse.config.texture_max_patch_px;
  j["textured_pixel_share"] = static_cast<double>(textured_px) / covered;
  j["psnr_vertex_db"] = err_vertex.psnrDb();
  j["psnr_texture_db"] = err_texture.psnrDb();
  j["psnr_exported_obj_db"] = err_obj.psnrDb();
  j["gradient_energy_vertex"] = ge_vertex.mean();
  j["gradient_energy_texture"] = ge_texture.mean();
  j["gradient_energy_truth"] = ge_truth.mean();
  j["views"] = per_view;
  std::ofstream(fs::path(options.out_dir) / "texture_compare.json") << j.dump(2) << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CompareOptions options;
  CLI::App app("", "stereo_fusion_texture_compare");
  addCompareArguments(&app, &options);
  if (const auto exit_code = cli::parseOrExitCode(app, argc, argv)) return *exit_code;
  return compareTextures(std::move(options));
}
