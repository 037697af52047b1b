#include "simulator/AnalyticScene.h"

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>

namespace stereo_fusion::sim {

namespace {

class Plane : public Primitive {
 public:
  Plane(const Eigen::Vector3d& point, const Eigen::Vector3d& normal)
      : n_(normal.normalized()), c_(n_.dot(point)) {}
  double raycast(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min) const override {
    const double denom = n_.dot(d);
    if (std::abs(denom) < 1e-12) return INFINITY;
    const double t = (c_ - n_.dot(o)) / denom;
    return t > t_min ? t : INFINITY;
  }
  double signedDistance(const Eigen::Vector3d& p) const override { return n_.dot(p) - c_; }

 private:
  Eigen::Vector3d n_;
  double c_;
};

class Sphere : public Primitive {
 public:
  Sphere(const Eigen::Vector3d& c, double r) : c_(c), r_(r) {}
  double raycast(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min) const override {
    const Eigen::Vector3d oc = o - c_;
    const double b = oc.dot(d);
    const double disc = b * b - (oc.squaredNorm() - r_ * r_);
    if (disc < 0) return INFINITY;
    const double s = std::sqrt(disc);
    if (-b - s > t_min) return -b - s;
    if (-b + s > t_min) return -b + s;
    return INFINITY;
  }
  double signedDistance(const Eigen::Vector3d& p) const override { return (p - c_).norm() - r_; }

 private:
  Eigen::Vector3d c_;
  double r_;
};

class Box : public Primitive {
 public:
  Box(const Eigen::Isometry3d& T_world_box, const Eigen::Vector3d& half)
      : T_box_world_(T_world_box.inverse()), h_(half) {}
  double raycast(const Eigen::Vector3d& o_w, const Eigen::Vector3d& d_w,
                 double t_min) const override {
    const Eigen::Vector3d o = T_box_world_ * o_w;
    const Eigen::Vector3d d = T_box_world_.linear() * d_w;
    double t0 = -INFINITY, t1 = INFINITY;
    for (int a = 0; a < 3; ++a) {
      if (std::abs(d[a]) < 1e-15) {
        if (std::abs(o[a]) > h_[a]) return INFINITY;
        continue;
      }
      double ta = (-h_[a] - o[a]) / d[a], tb = (h_[a] - o[a]) / d[a];
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
    }
    if (t0 > t1) return INFINITY;
    if (t0 > t_min) return t0;
    if (t1 > t_min) return t1;
    return INFINITY;
  }
  double signedDistance(const Eigen::Vector3d& p_w) const override {
    const Eigen::Vector3d q = (T_box_world_ * p_w).cwiseAbs() - h_;
    return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
  }

 private:
  Eigen::Isometry3d T_box_world_;
  Eigen::Vector3d h_;
};

class Torus : public Primitive {
 public:
  Torus(const Eigen::Isometry3d& T_world_torus, double major, double minor)
      : T_torus_world_(T_world_torus.inverse()), R_(major), r_(minor) {}
  double signedDistance(const Eigen::Vector3d& p_w) const override {
    const Eigen::Vector3d p = T_torus_world_ * p_w;
    const double q = std::hypot(p.x(), p.y()) - R_;
    return std::hypot(q, p.z()) - r_;
  }
  double raycast(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min) const override {
    // Rays missing the bounding sphere miss the torus: skip the tracing for them.
    const Eigen::Vector3d oc = o - T_torus_world_.inverse().translation();
    const double bound = R_ + r_;
    const double b = oc.dot(d);
    const double disc = b * b - (oc.squaredNorm() - bound * bound);
    if (disc < 0.0) return INFINITY;
    const double t_exit = -b + std::sqrt(disc);
    if (t_exit <= t_min) return INFINITY;
    // Sphere tracing on the exact SDF, then bisection on the last step: exact to ~1e-9 m.
    double t = std::max(t_min, -b - std::sqrt(disc)) + 1e-9;
    double prev_t = t;
    double sd = signedDistance(o + t * d);
    const bool inside = sd < 0;
    for (int i = 0; i < 512 && t < t_exit + 1e-6; ++i) {
      const double step = std::max(std::abs(sd), 1e-7);
      prev_t = t;
      t += step;
      sd = signedDistance(o + t * d);
      if ((sd < 0) != inside) {
        double lo = prev_t, hi = t;
        for (int k = 0; k < 60; ++k) {
          const double mid = 0.5 * (lo + hi);
          ((signedDistance(o + mid * d) < 0) != inside ? hi : lo) = mid;
        }
        return 0.5 * (lo + hi);
      }
      if (std::abs(sd) < 1e-10) return t;
    }
    return INFINITY;
  }

 private:
  Eigen::Isometry3d T_torus_world_;
  double R_, r_;
};

/// Smooth 3D value noise in [0, 1] (hash of lattice points, trilinear with smoothstep).
double valueNoise(const Eigen::Vector3d& p) {
  const Eigen::Vector3d f = p.array().floor();
  const Eigen::Vector3d t = p - f;
  auto hash = [](int x, int y, int z) {
    uint32_t h = static_cast<uint32_t>(x) * 374761393u + static_cast<uint32_t>(y) * 668265263u +
                 static_cast<uint32_t>(z) * 2147483647u;
    h = (h ^ (h >> 13)) * 1274126177u;
    return ((h ^ (h >> 16)) & 0xffffff) / double(0xffffff);
  };
  auto smooth = [](double x) { return x * x * (3 - 2 * x); };
  const double sx = smooth(t.x()), sy = smooth(t.y()), sz = smooth(t.z());
  const int x = static_cast<int>(f.x()), y = static_cast<int>(f.y()), z = static_cast<int>(f.z());
  double acc = 0;
  for (int c = 0; c < 8; ++c) {
    const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
    acc += hash(x + dx, y + dy, z + dz) * (dx ? sx : 1 - sx) * (dy ? sy : 1 - sy) *
           (dz ? sz : 1 - sz);
  }
  return acc;
}

}  // namespace

std::unique_ptr<Primitive> makePlane(const Eigen::Vector3d& point, const Eigen::Vector3d& normal) {
  return std::make_unique<Plane>(point, normal);
}
std::unique_ptr<Primitive> makeSphere(const Eigen::Vector3d& centre, double radius) {
  return std::make_unique<Sphere>(centre, radius);
}
std::unique_ptr<Primitive> makeBox(const Eigen::Isometry3d& T_world_box,
                                   const Eigen::Vector3d& half_size) {
  return std::make_unique<Box>(T_world_box, half_size);
}
std::unique_ptr<Primitive> makeTorus(const Eigen::Isometry3d& T_world_torus, double major_m,
                                     double minor_m) {
  return std::make_unique<Torus>(T_world_torus, major_m, minor_m);
}

void AnalyticScene::add(std::unique_ptr<Primitive> primitive, const Eigen::Vector3d& rgb) {
  primitive->base_rgb = rgb;
  primitives_.push_back(std::move(primitive));
}

Hit AnalyticScene::raycast(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir) const {
  Hit hit;
  for (size_t i = 0; i < primitives_.size(); ++i) {
    const double t = primitives_[i]->raycast(origin, dir, 1e-9);
    if (t < hit.t) hit = {t, static_cast<int>(i)};
  }
  return hit;
}

double AnalyticScene::distanceToSurface(const Eigen::Vector3d& p) const {
  double best = INFINITY;
  for (const auto& prim : primitives_) best = std::min(best, std::abs(prim->signedDistance(p)));
  return best;
}

Eigen::Vector3d AnalyticScene::colorAt(const Eigen::Vector3d& p, int index) const {
  // Two octaves of value noise: texture at ~2 cm and ~10 cm scales, rich enough for SGBM.
  const double n = 0.6 * valueNoise(p * 50.0) + 0.4 * valueNoise(p * 10.0 + Eigen::Vector3d(7, 3, 1));
  return (primitives_[index]->base_rgb * (0.35 + 0.9 * n)).cwiseMin(255.0).cwiseMax(0.0);
}

void renderDepthAndColor(const AnalyticScene& scene, const StereoCamera& camera,
                         const Eigen::Isometry3d& T_world_camera, cv::Mat* depth_m,
                         cv::Mat* color_rgb) {
  depth_m->create(camera.height(), camera.width(), CV_32FC1);
  if (color_rgb) color_rgb->create(camera.height(), camera.width(), CV_8UC3);
  const Eigen::Vector3d origin = T_world_camera.translation();
  const Eigen::Matrix3d R = T_world_camera.linear();
  cv::parallel_for_(cv::Range(0, camera.height()), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      for (int u = 0; u < camera.width(); ++u) {
        const Eigen::Vector3d dir_c((u - camera.cx()) / camera.fx(), (v - camera.cy()) / camera.fy(), 1.0);
        const Eigen::Vector3d dir_c_n = dir_c.normalized();
        const Hit hit = scene.raycast(origin, R * dir_c_n);
        const bool ok = std::isfinite(hit.t);
        depth_m->at<float>(v, u) = ok ? static_cast<float>(hit.t * dir_c_n.z()) : 0.0f;
        if (color_rgb) {
          cv::Vec3b& px = color_rgb->at<cv::Vec3b>(v, u);
          if (ok) {
            const Eigen::Vector3d c = scene.colorAt(origin + hit.t * R * dir_c_n, hit.primitive);
            px = cv::Vec3b(static_cast<uint8_t>(c.x()), static_cast<uint8_t>(c.y()),
                           static_cast<uint8_t>(c.z()));
          } else {
            px = cv::Vec3b(0, 0, 0);
          }
        }
      }
    }
  });
}

cv::Mat disparityFromDepth(const cv::Mat& depth_m, const StereoCamera& camera) {
  cv::Mat disparity(depth_m.size(), CV_32FC1);
  for (int v = 0; v < depth_m.rows; ++v)
    for (int u = 0; u < depth_m.cols; ++u)
      disparity.at<float>(v, u) =
          static_cast<float>(camera.disparityFromDepth(depth_m.at<float>(v, u)));
  return disparity;
}

Eigen::Isometry3d lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                         const Eigen::Vector3d& up) {
  const Eigen::Vector3d z = (target - eye).normalized();
  Eigen::Vector3d x = z.cross(up);
  if (x.norm() < 1e-9) x = z.unitOrthogonal();  // looking straight along `up`
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);  // optical y points down when `up` points up
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = x;
  T.linear().col(1) = y;
  T.linear().col(2) = z;
  T.translation() = eye;
  return T;
}

}  // namespace stereo_fusion::sim
