#include "stereo_fusion/mesh/TextureStore.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "stereo_fusion/map/TruncationBand.h"
#include "stereo_fusion/util/Timer.h"

namespace stereo_fusion {

namespace {

/// A stored patch must beat this factor to be replaced: near-equal views would otherwise
/// swap patches (and republish them) every frame.
constexpr double kReplaceMargin = 1.1;

/// Texel density of `uv_px` (vertex pixel coordinates in a source image, `p_camera` the
/// vertices in that camera's frame): projected area of front-facing triangles per m² of
/// surface, px²/m². 0 for a degenerate submesh.
double texelDensity(const SubMesh& mesh, const std::vector<Eigen::Vector2d>& uv_px,
                    const std::vector<Eigen::Vector3d>& p_camera) {
  double area_m2 = 0, projected_px2 = 0;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d& a = p_camera[t[0]];
    const Eigen::Vector3d n = (p_camera[t[1]] - a).cross(p_camera[t[2]] - a);
    area_m2 += 0.5 * n.norm();
    // The triangle is wound counter-clockwise seen from free space, so its normal points to
    // the viewer when the view ray from the camera centre (the origin) meets it head-on.
    if (n.dot(a) >= 0) continue;
    const Eigen::Vector2d e1 = uv_px[t[1]] - uv_px[t[0]], e2 = uv_px[t[2]] - uv_px[t[0]];
    projected_px2 += 0.5 * std::abs(e1.x() * e2.y() - e1.y() * e2.x());
  }
  return area_m2 > 0 ? projected_px2 / area_m2 : 0.0;
}

/// Scratch buffers of one worker chunk, reused across its blocks.
struct Scratch {
  std::vector<Eigen::Vector2d> uv_px;
  std::vector<Eigen::Vector3d> p_camera;
};

/// Re-scores `patch` for the (possibly changed) vertices of `mesh` and writes their UVs to
/// `uvs`. False when a vertex leaves the patch or its camera.
bool reprojectPatch(const TexturePatch& patch, const SubMesh& mesh,
                    std::vector<Eigen::Vector2f>* uvs, double* score, Scratch* s) {
  const size_t n = mesh.positions.size();
  uvs->resize(n);
  s->uv_px.resize(n);
  s->p_camera.resize(n);
  for (size_t v = 0; v < n; ++v) {
    const Eigen::Vector3d p = patch.T_camera_world * mesh.positions[v].cast<double>();
    if (!(p.z() > 0)) return false;
    const Eigen::Vector2d px(patch.fx_px * p.x() / p.z() + patch.cx_px,
                             patch.fy_px * p.y() / p.z() + patch.cy_px);
    const Eigen::Vector2d uv = (px - patch.crop_origin_px + Eigen::Vector2d::Constant(0.5))
                                   .cwiseQuotient(patch.crop_size_px);
    if (!(uv.x() >= 0 && uv.x() <= 1 && uv.y() >= 0 && uv.y() <= 1)) return false;
    (*uvs)[v] = uv.cast<float>();
    s->uv_px[v] = px;
    s->p_camera[v] = p;
  }
  const double k = patch.image_rgb.cols / patch.crop_size_px.x();
  *score = texelDensity(mesh, s->uv_px, s->p_camera) * k * k;
  return true;
}

/// Outcome of the current frame for one block.
struct Candidate {
  bool ok = false;
  bool occluded = false;
  double score = 0;
  cv::Rect crop;
};

Candidate evaluateFrame(const SubMesh& mesh, const StereoFrame& frame,
                        const Eigen::Isometry3d& T_camera_world, const TextureParams& params,
                        Scratch* s) {
  Candidate c;
  const StereoCamera& cam = frame.camera;
  const size_t n = mesh.positions.size();
  s->uv_px.resize(n);
  s->p_camera.resize(n);
  const double tolerance_m =
      TruncationBand(params.voxel_size_m, params.truncation_vox).measurementM(mesh.level);
  Eigen::Vector2d lo(INFINITY, INFINITY), hi(-INFINITY, -INFINITY);
  for (size_t v = 0; v < n; ++v) {
    const Eigen::Vector3d p = T_camera_world * mesh.positions[v].cast<double>();
    Eigen::Vector2d uv;
    if (!cam.project(p, &uv) || !cam.isInImage(uv, params.border_px)) return c;
    // Occlusion: any measured surface around the vertex's pixel clearly in front of it means
    // this frame sees something else there (the occluder's colour, or its edge blended in).
    const int pu = static_cast<int>(std::floor(uv.x() + 0.5)),
              pv = static_cast<int>(std::floor(uv.y() + 0.5));
    for (int y = std::max(pv - 1, 0); y <= std::min(pv + 1, cam.height() - 1); ++y) {
      const float* row = frame.disparity_px.ptr<float>(y);
      for (int x = std::max(pu - 1, 0); x <= std::min(pu + 1, cam.width() - 1); ++x) {
        const double z = cam.depthFromDisparity(row[x]);
        if (std::isfinite(z) && z < p.z() - tolerance_m) {
          c.occluded = true;
          return c;
        }
      }
    }
    s->uv_px[v] = uv;
    s->p_camera[v] = p;
    lo = lo.cwiseMin(uv);
    hi = hi.cwiseMax(uv);
  }
  if (n == 0) return c;
  // One texel of margin on every side so bilinear sampling at a vertex stays inside the patch.
  const int x0 = std::max(0, static_cast<int>(std::floor(lo.x())) - 1);
  const int y0 = std::max(0, static_cast<int>(std::floor(lo.y())) - 1);
  const int x1 = std::min(cam.width(), static_cast<int>(std::ceil(hi.x())) + 2);
  const int y1 = std::min(cam.height(), static_cast<int>(std::ceil(hi.y())) + 2);
  c.crop = cv::Rect(x0, y0, x1 - x0, y1 - y0);
  const double k = std::min(
      1.0, static_cast<double>(params.max_patch_px) / std::max(c.crop.width, c.crop.height));
  c.score = texelDensity(mesh, s->uv_px, s->p_camera) * k * k;
  c.ok = c.score > 0;
  return c;
}

TexturePatch cutPatch(const SubMesh& mesh, const StereoFrame& frame,
                      const Eigen::Isometry3d& T_camera_world, const Candidate& c,
                      uint64_t frame_index, const TextureParams& params, const Scratch& s) {
  TexturePatch patch;
  const cv::Mat crop = frame.color(c.crop);
  cv::Mat rgb;
  if (crop.channels() == 1) {
    cv::cvtColor(crop, rgb, cv::COLOR_GRAY2RGB);
  } else {
    rgb = crop;
  }
  const int edge = std::max(c.crop.width, c.crop.height);
  if (edge > params.max_patch_px) {
    const double k = static_cast<double>(params.max_patch_px) / edge;
    const cv::Size size(std::max(1, static_cast<int>(std::lround(c.crop.width * k))),
                        std::max(1, static_cast<int>(std::lround(c.crop.height * k))));
    cv::resize(rgb, patch.image_rgb, size, 0, 0, cv::INTER_AREA);
  } else {
    patch.image_rgb = rgb.clone();
  }
  patch.T_camera_world = T_camera_world;
  patch.fx_px = frame.camera.fx();
  patch.fy_px = frame.camera.fy();
  patch.cx_px = frame.camera.cx();
  patch.cy_px = frame.camera.cy();
  patch.crop_origin_px = Eigen::Vector2d(c.crop.x, c.crop.y);
  patch.crop_size_px = Eigen::Vector2d(c.crop.width, c.crop.height);
  patch.score_px2_per_m2 = c.score;
  patch.frame_index = frame_index;
  // u = (x − x0 + ½) / crop width: texel-edge convention, unchanged by resizing the crop.
  patch.uvs.resize(mesh.positions.size());
  for (size_t v = 0; v < mesh.positions.size(); ++v)
    patch.uvs[v] = ((s.uv_px[v] - patch.crop_origin_px + Eigen::Vector2d::Constant(0.5))
                        .cwiseQuotient(patch.crop_size_px))
                       .cast<float>();
  return patch;
}

enum class Outcome { kNone, kNew, kReprojected };

struct BlockResult {
  Outcome outcome = Outcome::kNone;
  bool occluded = false;
  TexturePatch patch;                // kNew
  std::vector<Eigen::Vector2f> uvs;  // kReprojected
  double score = 0;                  // kReprojected
};

}  // namespace

bool projectIntoPatch(const TexturePatch& patch, const Eigen::Vector3f& p_world,
                      Eigen::Vector2f* uv) {
  const Eigen::Vector3d p = patch.T_camera_world * p_world.cast<double>();
  if (!(p.z() > 0)) return false;
  const Eigen::Vector2d px(patch.fx_px * p.x() / p.z() + patch.cx_px,
                           patch.fy_px * p.y() / p.z() + patch.cy_px);
  *uv = ((px - patch.crop_origin_px + Eigen::Vector2d::Constant(0.5))
             .cwiseQuotient(patch.crop_size_px))
            .cast<float>();
  return true;
}

TextureStats TextureStore::update(const MeshStore& meshes, const MeshChanges& changes,
                                  const StereoFrame& frame, uint64_t frame_index,
                                  ThreadPool* pool) {
  Timer timer;
  TextureStats stats;
  for (const BlockKey& key : changes.removed) patches_.erase(key);
  const bool frame_has_color = !frame.color.empty();
  const Eigen::Isometry3d T_camera_world = frame.T_world_camera.inverse();
  std::vector<BlockResult> results(changes.changed.size());
  pool->parallelFor(changes.changed.size(), 4, [&](size_t begin, size_t end) {
    Scratch scratch;
    for (size_t i = begin; i < end; ++i) {
      const BlockKey& key = changes.changed[i];
      const auto mesh_it = meshes.submeshes().find(key);
      if (mesh_it == meshes.submeshes().end()) continue;
      const SubMesh& mesh = mesh_it->second;
      BlockResult& r = results[i];
      const auto stored_it = patches_.find(key);  // read-only while the workers run
      bool stored_fits = false;
      if (stored_it != patches_.end())
        stored_fits = reprojectPatch(stored_it->second, mesh, &r.uvs, &r.score, &scratch);
      if (frame_has_color) {
        const Candidate c = evaluateFrame(mesh, frame, T_camera_world, params_, &scratch);
        r.occluded = c.occluded;
        if (c.ok && (!stored_fits || c.score > kReplaceMargin * r.score)) {
          r.patch = cutPatch(mesh, frame, T_camera_world, c, frame_index, params_, scratch);
          r.outcome = Outcome::kNew;
          continue;
        }
      }
      if (stored_fits) r.outcome = Outcome::kReprojected;
    }
  });
  for (size_t i = 0; i < results.size(); ++i) {
    const BlockKey& key = changes.changed[i];
    BlockResult& r = results[i];
    stats.occluded += r.occluded;
    switch (r.outcome) {
      case Outcome::kNew:
        patches_[key] = std::move(r.patch);
        ++stats.retextured;
        break;
      case Outcome::kReprojected: {
        TexturePatch& p = patches_.at(key);
        p.uvs = std::move(r.uvs);
        p.score_px2_per_m2 = r.score;
        ++stats.reprojected;
        break;
      }
      case Outcome::kNone:
        patches_.erase(key);
        ++stats.untextured;
        break;
    }
  }
  stats.texture_ms = timer.elapsedMs();
  return stats;
}

void TextureStore::reprojectAll(const MeshStore& meshes) {
  Scratch scratch;
  for (auto it = patches_.begin(); it != patches_.end();) {
    const auto mesh_it = meshes.submeshes().find(it->first);
    std::vector<Eigen::Vector2f> uvs;
    double score = 0;
    if (mesh_it != meshes.submeshes().end() &&
        reprojectPatch(it->second, mesh_it->second, &uvs, &score, &scratch)) {
      it->second.uvs = std::move(uvs);
      it->second.score_px2_per_m2 = score;
      ++it;
    } else {
      it = patches_.erase(it);
    }
  }
}

const TexturePatch* TextureStore::find(const BlockKey& key) const {
  const auto it = patches_.find(key);
  return it == patches_.end() ? nullptr : &it->second;
}

std::optional<TexturePatch> TextureStore::detach(const BlockKey& key) {
  const auto it = patches_.find(key);
  if (it == patches_.end()) return std::nullopt;
  std::optional<TexturePatch> patch(std::move(it->second));
  patches_.erase(it);
  return patch;
}

size_t TextureStore::memoryBytes() const {
  size_t bytes = 0;
  for (const auto& [key, patch] : patches_) bytes += patch.memoryBytes() + sizeof(TexturePatch);
  return bytes;
}

}  // namespace stereo_fusion
