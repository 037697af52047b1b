#include "simulator/AnalyticScene.h"

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>

#include "stereo_fusion/mesh/SubMesh.h"

namespace stereo_fusion::sim {

namespace {

/// Narrows the ray interval [t0, t1] to the slab |o + t·d| ≤ h of one axis. False when the ray
/// runs parallel to the slab outside it.
bool clipToSlab(double o, double d, double h, double* t0, double* t1) {
  if (std::abs(d) < 1e-15) return std::abs(o) <= h;
  double ta = (-h - o) / d, tb = (h - o) / d;
  if (ta > tb) std::swap(ta, tb);
  *t0 = std::max(*t0, ta);
  *t1 = std::min(*t1, tb);
  return true;
}

/// First ray parameter after t_min of a solid whose ray interval is [t0, t1] (entry, exit):
/// the entry, or the exit when the ray starts inside.
double firstHitInInterval(double t0, double t1, double t_min) {
  if (t0 > t1) return INFINITY;
  if (t0 > t_min) return t0;
  if (t1 > t_min) return t1;
  return INFINITY;
}

/// Appends vertices and triangles of one primitive to a mesh. Triangles are oriented so their
/// geometric normal agrees with their vertices' normals: the generators below then need not
/// get every winding right by hand, and inside-out primitives only flip the normals.
class MeshAppender {
 public:
  MeshAppender(TriangleMesh* mesh, const Eigen::Vector3d& rgb) : mesh_(mesh) {
    for (int c = 0; c < 3; ++c)
      rgb_[c] = static_cast<uint8_t>(std::clamp(std::lround(rgb[c]), 0L, 255L));
  }
  uint32_t vertex(const Eigen::Vector3d& p, const Eigen::Vector3d& n) {
    mesh_->positions.push_back(p.cast<float>());
    mesh_->normals.push_back(n.normalized().cast<float>());
    mesh_->colors.push_back(rgb_);
    return static_cast<uint32_t>(mesh_->positions.size() - 1);
  }
  void triangle(uint32_t a, uint32_t b, uint32_t c) {
    const auto& P = mesh_->positions;
    const auto& N = mesh_->normals;
    const Eigen::Vector3f face = (P[b] - P[a]).cross(P[c] - P[a]);
    if (face.dot(N[a] + N[b] + N[c]) < 0) std::swap(b, c);
    mesh_->triangles.push_back({a, b, c});
  }
  /// Two triangles of the quad a-b-c-d (in order around it).
  void quad(uint32_t a, uint32_t b, uint32_t c, uint32_t d) {
    triangle(a, b, c);
    triangle(a, c, d);
  }

 private:
  TriangleMesh* mesh_;
  std::array<uint8_t, 3> rgb_{};
};

/// Number of segments for a curve of `length_m`: steps of at most `max_edge_m`, at least
/// `min_segments` (keeps small curved primitives round).
int segments(double length_m, double max_edge_m, int min_segments) {
  return std::max(min_segments, static_cast<int>(std::ceil(length_m / max_edge_m - 1e-9)));
}

/// Below 1 mm a tessellation would explode in size without being more useful as ground truth.
double sanitizeEdge(double max_edge_m) { return std::max(max_edge_m, 1e-3); }

/// Curved surfaces get at least this many segments around a full circle (15° steps).
constexpr int kMinSegmentsAround = 24;

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
  void tessellate(TriangleMesh* mesh, double max_edge_m) const override {
    // Latitude/longitude grid with a vertex at each pole.
    const double e = sanitizeEdge(max_edge_m);
    const int n_lon = segments(2 * M_PI * r_, e, kMinSegmentsAround);
    const int n_lat = segments(M_PI * r_, e, kMinSegmentsAround / 2);
    MeshAppender out(mesh, base_rgb);
    const uint32_t north = out.vertex(c_ + r_ * Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitZ());
    const uint32_t first_ring = north + 1;
    for (int i = 1; i < n_lat; ++i) {
      const double polar = M_PI * i / n_lat;
      for (int j = 0; j < n_lon; ++j) {
        const double az = 2 * M_PI * j / n_lon;
        const Eigen::Vector3d n(std::sin(polar) * std::cos(az), std::sin(polar) * std::sin(az),
                                std::cos(polar));
        out.vertex(c_ + r_ * n, n);
      }
    }
    const uint32_t south =
        out.vertex(c_ - r_ * Eigen::Vector3d::UnitZ(), -Eigen::Vector3d::UnitZ());
    auto ring = [&](int i, int j) { return first_ring + (i - 1) * n_lon + (j % n_lon); };
    for (int j = 0; j < n_lon; ++j) {
      out.triangle(north, ring(1, j), ring(1, j + 1));
      out.triangle(south, ring(n_lat - 1, j + 1), ring(n_lat - 1, j));
      for (int i = 1; i + 1 < n_lat; ++i)
        out.quad(ring(i, j), ring(i + 1, j), ring(i + 1, j + 1), ring(i, j + 1));
    }
  }

 private:
  Eigen::Vector3d c_;
  double r_;
};

class Box : public Primitive {
 public:
  /// `inside_out`: the solid is the complement of the box (a room); only the sign of the
  /// distance and the tessellated normals change, the surface is the same.
  Box(const Eigen::Isometry3d& T_world_box, const Eigen::Vector3d& half, bool inside_out = false)
      : T_world_box_(T_world_box),
        T_box_world_(T_world_box.inverse()),
        h_(half),
        inside_out_(inside_out) {}
  double raycast(const Eigen::Vector3d& o_w, const Eigen::Vector3d& d_w,
                 double t_min) const override {
    const Eigen::Vector3d o = T_box_world_ * o_w;
    const Eigen::Vector3d d = T_box_world_.linear() * d_w;
    double t0 = -INFINITY, t1 = INFINITY;
    for (int a = 0; a < 3; ++a)
      if (!clipToSlab(o[a], d[a], h_[a], &t0, &t1)) return INFINITY;
    return firstHitInInterval(t0, t1, t_min);
  }
  double signedDistance(const Eigen::Vector3d& p_w) const override {
    const Eigen::Vector3d q = (T_box_world_ * p_w).cwiseAbs() - h_;
    const double sd = q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
    return inside_out_ ? -sd : sd;
  }
  void tessellate(TriangleMesh* mesh, double max_edge_m) const override {
    // Each face is its own grid (vertices are not shared across the edges): per-face normals.
    const double e = sanitizeEdge(max_edge_m);
    MeshAppender out(mesh, base_rgb);
    for (int a = 0; a < 3; ++a) {
      const int b = (a + 1) % 3, c = (a + 2) % 3;
      const int nb = segments(2 * h_[b], e, 1), nc = segments(2 * h_[c], e, 1);
      for (const double side : {-1.0, 1.0}) {
        Eigen::Vector3d n_box = Eigen::Vector3d::Zero();
        n_box[a] = inside_out_ ? -side : side;
        const Eigen::Vector3d n_world = T_world_box_.linear() * n_box;
        const uint32_t first = static_cast<uint32_t>(mesh->positions.size());
        for (int j = 0; j <= nc; ++j)
          for (int i = 0; i <= nb; ++i) {
            Eigen::Vector3d p;
            p[a] = side * h_[a];
            p[b] = -h_[b] + 2 * h_[b] * i / nb;
            p[c] = -h_[c] + 2 * h_[c] * j / nc;
            out.vertex(T_world_box_ * p, n_world);
          }
        auto at = [&](int i, int j) { return first + j * (nb + 1) + i; };
        for (int j = 0; j < nc; ++j)
          for (int i = 0; i < nb; ++i)
            out.quad(at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
      }
    }
  }

 private:
  Eigen::Isometry3d T_world_box_;
  Eigen::Isometry3d T_box_world_;
  Eigen::Vector3d h_;
  bool inside_out_;
};

class Cylinder : public Primitive {
 public:
  Cylinder(const Eigen::Isometry3d& T_world_cylinder, double radius, double half_height)
      : T_world_cyl_(T_world_cylinder),
        T_cyl_world_(T_world_cylinder.inverse()),
        r_(radius),
        h_(half_height) {}
  double raycast(const Eigen::Vector3d& o_w, const Eigen::Vector3d& d_w,
                 double t_min) const override {
    // The ray's interval inside the solid is the intersection of its intervals inside the
    // slab |z| <= h and inside the infinite cylinder; like Box, return its entry, or its exit
    // when the ray starts inside.
    const Eigen::Vector3d o = T_cyl_world_ * o_w;
    const Eigen::Vector3d d = T_cyl_world_.linear() * d_w;
    double t0 = -INFINITY, t1 = INFINITY;
    if (!clipToSlab(o.z(), d.z(), h_, &t0, &t1)) return INFINITY;
    const double a = d.x() * d.x() + d.y() * d.y();
    const double b = o.x() * d.x() + o.y() * d.y();
    const double c = o.x() * o.x() + o.y() * o.y() - r_ * r_;
    if (a < 1e-15) {
      if (c > 0) return INFINITY;  // parallel to the axis, outside the radius
    } else {
      const double disc = b * b - a * c;
      if (disc < 0) return INFINITY;
      // Cancellation-free roots of a·t² + 2b·t + c = 0.
      const double q = -(b + std::copysign(std::sqrt(disc), b));
      double ta = q / a, tb = (q != 0.0) ? c / q : ta;
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
    }
    return firstHitInInterval(t0, t1, t_min);
  }
  double signedDistance(const Eigen::Vector3d& p_w) const override {
    const Eigen::Vector3d p = T_cyl_world_ * p_w;
    const double dr = std::hypot(p.x(), p.y()) - r_;
    const double dz = std::abs(p.z()) - h_;
    return std::min(std::max(dr, dz), 0.0) + std::hypot(std::max(dr, 0.0), std::max(dz, 0.0));
  }
  void tessellate(TriangleMesh* mesh, double max_edge_m) const override {
    // Side: rings along z; caps: concentric rings around a centre vertex. Side and caps have
    // separate vertices on the rims (different normals) at identical positions.
    const double e = sanitizeEdge(max_edge_m);
    const int n_around = segments(2 * M_PI * r_, e, kMinSegmentsAround);
    const int n_z = segments(2 * h_, e, 1);
    const int n_rings = segments(r_, e, 1);
    MeshAppender out(mesh, base_rgb);
    auto rim = [&](int j, double radius, double z) {
      const double az = 2 * M_PI * (j % n_around) / n_around;
      return Eigen::Vector3d(radius * std::cos(az), radius * std::sin(az), z);
    };
    const Eigen::Matrix3d& R = T_world_cyl_.linear();
    const uint32_t side0 = static_cast<uint32_t>(mesh->positions.size());
    for (int k = 0; k <= n_z; ++k)
      for (int j = 0; j < n_around; ++j) {
        const Eigen::Vector3d p = rim(j, r_, -h_ + 2 * h_ * k / n_z);
        out.vertex(T_world_cyl_ * p, R * Eigen::Vector3d(p.x(), p.y(), 0));
      }
    auto side = [&](int k, int j) { return side0 + k * n_around + (j % n_around); };
    for (int k = 0; k < n_z; ++k)
      for (int j = 0; j < n_around; ++j)
        out.quad(side(k, j), side(k, j + 1), side(k + 1, j + 1), side(k + 1, j));
    for (const double sign : {-1.0, 1.0}) {
      const Eigen::Vector3d n = R * Eigen::Vector3d(0, 0, sign);
      const uint32_t centre = out.vertex(T_world_cyl_ * Eigen::Vector3d(0, 0, sign * h_), n);
      for (int ring = 1; ring <= n_rings; ++ring)
        for (int j = 0; j < n_around; ++j)
          out.vertex(T_world_cyl_ * rim(j, ring == n_rings ? r_ : r_ * ring / n_rings, sign * h_),
                     n);
      auto at = [&](int ring, int j) {
        return centre + 1 + (ring - 1) * n_around + (j % n_around);
      };
      for (int j = 0; j < n_around; ++j) {
        out.triangle(centre, at(1, j), at(1, j + 1));
        for (int ring = 1; ring < n_rings; ++ring)
          out.quad(at(ring, j), at(ring + 1, j), at(ring + 1, j + 1), at(ring, j + 1));
      }
    }
  }

 private:
  Eigen::Isometry3d T_world_cyl_;
  Eigen::Isometry3d T_cyl_world_;
  double r_, h_;
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
  void tessellate(TriangleMesh* mesh, double max_edge_m) const override {
    // Grid over the angle around the ring (theta) and around the tube (phi).
    const double e = sanitizeEdge(max_edge_m);
    const int n_major = segments(2 * M_PI * (R_ + r_), e, kMinSegmentsAround);
    const int n_minor = segments(2 * M_PI * r_, e, kMinSegmentsAround);
    const Eigen::Isometry3d T_world_torus = T_torus_world_.inverse();
    MeshAppender out(mesh, base_rgb);
    const uint32_t first = static_cast<uint32_t>(mesh->positions.size());
    for (int i = 0; i < n_major; ++i) {
      const double theta = 2 * M_PI * i / n_major;
      for (int j = 0; j < n_minor; ++j) {
        const double phi = 2 * M_PI * j / n_minor;
        const Eigen::Vector3d n(std::cos(phi) * std::cos(theta), std::cos(phi) * std::sin(theta),
                                std::sin(phi));
        const Eigen::Vector3d ring(R_ * std::cos(theta), R_ * std::sin(theta), 0.0);
        out.vertex(T_world_torus * (ring + r_ * n), T_world_torus.linear() * n);
      }
    }
    auto at = [&](int i, int j) { return first + (i % n_major) * n_minor + (j % n_minor); };
    for (int i = 0; i < n_major; ++i)
      for (int j = 0; j < n_minor; ++j)
        out.quad(at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
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
    acc +=
        hash(x + dx, y + dy, z + dz) * (dx ? sx : 1 - sx) * (dy ? sy : 1 - sy) * (dz ? sz : 1 - sz);
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
std::unique_ptr<Primitive> makeRoom(const Eigen::Isometry3d& T_world_room,
                                    const Eigen::Vector3d& half_size) {
  return std::make_unique<Box>(T_world_room, half_size, /*inside_out=*/true);
}
std::unique_ptr<Primitive> makeCylinder(const Eigen::Isometry3d& T_world_cylinder, double radius_m,
                                        double half_height_m) {
  return std::make_unique<Cylinder>(T_world_cylinder, radius_m, half_height_m);
}
std::unique_ptr<Primitive> makeTorus(const Eigen::Isometry3d& T_world_torus, double major_m,
                                     double minor_m) {
  return std::make_unique<Torus>(T_world_torus, major_m, minor_m);
}

void Primitive::tessellate(TriangleMesh* /*mesh*/, double /*max_edge_m*/) const {}

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

double AnalyticScene::clearance(const Eigen::Vector3d& p) const {
  double best = INFINITY;
  for (const auto& prim : primitives_) best = std::min(best, prim->signedDistance(p));
  return best;
}

void AnalyticScene::tessellate(TriangleMesh* mesh, double max_edge_m) const {
  for (size_t i = 0; i < primitives_.size(); ++i) {
    const size_t first = mesh->positions.size();
    primitives_[i]->tessellate(mesh, max_edge_m);
    for (size_t v = first; v < mesh->positions.size(); ++v) {
      const Eigen::Vector3d c = colorAt(mesh->positions[v].cast<double>(), static_cast<int>(i));
      mesh->colors[v] = {static_cast<uint8_t>(c.x()), static_cast<uint8_t>(c.y()),
                         static_cast<uint8_t>(c.z())};
    }
  }
}

Eigen::Vector3d AnalyticScene::colorAt(const Eigen::Vector3d& p, int index) const {
  // Two octaves of value noise: texture at ~2 cm and ~10 cm scales, rich enough for SGBM.
  const double n =
      0.6 * valueNoise(p * 50.0) + 0.4 * valueNoise(p * 10.0 + Eigen::Vector3d(7, 3, 1));
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
        const Eigen::Vector3d dir_c((u - camera.cx()) / camera.fx(),
                                    (v - camera.cy()) / camera.fy(), 1.0);
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
