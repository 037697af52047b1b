#include "simulator/Trajectory.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace stereo_fusion::sim {

namespace {

/// Uniform [lo, hi) from mt19937's 32-bit words: identical for a seed with any standard
/// library (std::uniform_real_distribution is implementation-defined).
double uniform(std::mt19937* rng, double lo, double hi) {
  return lo + (hi - lo) * ((*rng)() / 4294967296.0);
}

/// Point of the closed uniform Catmull–Rom spline through `p` at parameter s ∈ [0, n).
Eigen::Vector3d catmullRom(const std::vector<Eigen::Vector3d>& p, double s) {
  const int n = static_cast<int>(p.size());
  const int i = std::min(static_cast<int>(std::floor(s)), n - 1);
  const double t = s - i;
  const Eigen::Vector3d& p0 = p[(i + n - 1) % n];
  const Eigen::Vector3d& p1 = p[i];
  const Eigen::Vector3d& p2 = p[(i + 1) % n];
  const Eigen::Vector3d& p3 = p[(i + 2) % n];
  return 0.5 * (2 * p1 + (p2 - p0) * t + (2 * p0 - 5 * p1 + 4 * p2 - p3) * t * t +
                (3 * p1 - p0 - 3 * p2 + p3) * t * t * t);
}

/// Dense samples of a closed curve with their cumulative arc length, for arc-length sampling
/// (constant speed) and for the clearance check.
struct DenseCurve {
  std::vector<Eigen::Vector3d> points;
  std::vector<double> arc_m;  ///< arc length from the start to points[i]
};

DenseCurve densify(const std::vector<Eigen::Vector3d>& waypoints, int per_segment) {
  DenseCurve c;
  const int total = static_cast<int>(waypoints.size()) * per_segment;
  for (int i = 0; i <= total; ++i) {
    c.points.push_back(catmullRom(waypoints, std::fmod(static_cast<double>(i) / per_segment,
                                                       static_cast<double>(waypoints.size()))));
    c.arc_m.push_back(i == 0 ? 0.0 : c.arc_m.back() + (c.points[i] - c.points[i - 1]).norm());
  }
  return c;
}

/// Dense samples of the closed centripetal Catmull–Rom spline through `p` (Barry–Goldman form,
/// knot spacing |p_{i+1} − p_i|^½), `per_segment` samples per span.
DenseCurve densifyCentripetal(const std::vector<Eigen::Vector3d>& p, int per_segment) {
  const int n = static_cast<int>(p.size());
  DenseCurve c;
  auto point = [&](int i) -> const Eigen::Vector3d& { return p[((i % n) + n) % n]; };
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d &p0 = point(i - 1), &p1 = point(i), &p2 = point(i + 1),
                          &p3 = point(i + 2);
    const double t0 = 0.0, t1 = t0 + std::sqrt(std::max((p1 - p0).norm(), 1e-9)),
                 t2 = t1 + std::sqrt(std::max((p2 - p1).norm(), 1e-9)),
                 t3 = t2 + std::sqrt(std::max((p3 - p2).norm(), 1e-9));
    for (int k = 0; k < per_segment; ++k) {
      const double t = t1 + (t2 - t1) * k / per_segment;
      const Eigen::Vector3d a1 = ((t1 - t) * p0 + (t - t0) * p1) / (t1 - t0);
      const Eigen::Vector3d a2 = ((t2 - t) * p1 + (t - t1) * p2) / (t2 - t1);
      const Eigen::Vector3d a3 = ((t3 - t) * p2 + (t - t2) * p3) / (t3 - t2);
      const Eigen::Vector3d b1 = ((t2 - t) * a1 + (t - t0) * a2) / (t2 - t0);
      const Eigen::Vector3d b2 = ((t3 - t) * a2 + (t - t1) * a3) / (t3 - t1);
      c.points.push_back(((t2 - t) * b1 + (t - t1) * b2) / (t2 - t1));
    }
  }
  c.points.push_back(p.front());  // closed: the last sample is the first point again
  for (size_t i = 0; i < c.points.size(); ++i)
    c.arc_m.push_back(i == 0 ? 0.0 : c.arc_m.back() + (c.points[i] - c.points[i - 1]).norm());
  return c;
}

constexpr int kTourSamplesPerSegment = 64;

/// Position at arc length `s_m` along the closed curve (wrapped; linear between samples).
Eigen::Vector3d positionAt(const DenseCurve& c, double s_m) {
  const double length = c.arc_m.back();
  s_m = std::fmod(s_m, length);
  if (s_m < 0) s_m += length;
  const auto it = std::upper_bound(c.arc_m.begin(), c.arc_m.end(), s_m);
  const size_t i =
      std::clamp<size_t>(static_cast<size_t>(it - c.arc_m.begin()), 1, c.arc_m.size() - 1);
  const double len = c.arc_m[i] - c.arc_m[i - 1];
  const double t = len > 0 ? (s_m - c.arc_m[i - 1]) / len : 0.0;
  return c.points[i - 1] + t * (c.points[i] - c.points[i - 1]);
}

}  // namespace

std::vector<TimedPose> makeOrbit(const OrbitParams& params, int frames, double rate_hz,
                                 uint32_t seed) {
  std::mt19937 rng(seed);
  const double start_rad = uniform(&rng, 0, 2 * M_PI);
  const double direction = uniform(&rng, 0, 1) < 0.5 ? -1.0 : 1.0;
  const double radius_phase = uniform(&rng, 0, 2 * M_PI);
  const double height_phase = uniform(&rng, 0, 2 * M_PI);
  std::vector<TimedPose> poses;
  poses.reserve(std::max(frames, 0));
  for (int k = 0; k < frames; ++k) {
    const double f = static_cast<double>(k) / frames;  // the last frame does not repeat the first
    const double angle = start_rad + direction * 2 * M_PI * params.revolutions * f;
    const double radius = params.radius_m * (1 + 0.1 * std::sin(2 * M_PI * f + radius_phase));
    const double height = params.height_m * (1 + 0.1 * std::sin(4 * M_PI * f + height_phase));
    const Eigen::Vector3d eye = params.centre_m + Eigen::Vector3d(radius * std::cos(angle),
                                                                  radius * std::sin(angle), height);
    poses.push_back({k / rate_hz, lookAt(eye, params.centre_m)});
  }
  return poses;
}

std::optional<std::vector<TimedPose>> makeWalkthrough(const AnalyticScene& scene,
                                                      const WalkthroughParams& params, int frames,
                                                      double rate_hz, uint32_t seed,
                                                      std::string* error) {
  std::mt19937 rng(seed);
  const Eigen::Vector3d lo = params.free_space_m.min(), hi = params.free_space_m.max();
  const double c = params.clearance_m;
  const double z_lo = std::max(params.min_height_m, lo.z() + c);
  const double z_hi = std::min(params.max_height_m, hi.z() - c);
  if (hi.x() - lo.x() <= 2 * c || hi.y() - lo.y() <= 2 * c || z_hi < z_lo) {
    *error = "walkthrough: the free space is too small for the clearance";
    return std::nullopt;
  }
  const Eigen::Vector3d centre = params.free_space_m.center();
  // Waypoints sit on a randomly squashed ellipse around the centre, in angle order: a loop
  // without self-crossings or hairpins, which keeps the heading smooth.
  const double semi_x = (hi.x() - lo.x()) / 2 - c, semi_y = (hi.y() - lo.y()) / 2 - c;
  const int n = std::max(params.waypoints, 3);
  constexpr int kSamplesPerSegment = 64;
  for (int attempt = 0; attempt < params.max_attempts; ++attempt) {
    const double start_rad = uniform(&rng, 0, 2 * M_PI);
    std::vector<Eigen::Vector3d> waypoints;
    for (int i = 0; i < n; ++i) {
      const double angle = start_rad + 2 * M_PI * (i + uniform(&rng, -0.3, 0.3)) / n;
      const double scale = uniform(&rng, 0.35, 1.0);
      waypoints.emplace_back(centre.x() + scale * semi_x * std::cos(angle),
                             centre.y() + scale * semi_y * std::sin(angle),
                             uniform(&rng, z_lo, z_hi));
    }
    const DenseCurve curve = densify(waypoints, kSamplesPerSegment);
    const bool clear =
        std::all_of(curve.points.begin(), curve.points.end(), [&](const Eigen::Vector3d& p) {
          return params.free_space_m.contains(p) && scene.clearance(p) >= c;
        });
    if (!clear) continue;

    const double sweep_phase = uniform(&rng, 0, 2 * M_PI);
    std::vector<TimedPose> poses;
    poses.reserve(std::max(frames, 0));
    for (int k = 0; k < frames; ++k) {
      const double t_s = k / rate_hz;
      const double s_m = params.speed_mps * t_s;
      const Eigen::Vector3d eye = positionAt(curve, s_m);
      Eigen::Vector3d ahead = positionAt(curve, s_m + params.heading_window_m) -
                              positionAt(curve, s_m - params.heading_window_m);
      ahead.z() = 0;
      // Look ahead, turned inwards (angle-ordered waypoints make the loop counter-clockwise seen
      // from above, so inwards is to the left: +yaw), swept side to side to see around.
      const double yaw = std::atan2(ahead.y(), ahead.x()) + params.inward_turn_rad +
                         params.sweep_amplitude_rad *
                             std::sin(2 * M_PI * t_s / params.sweep_period_s + sweep_phase);
      const Eigen::Vector3d forward(std::cos(yaw) * std::cos(params.pitch_down_rad),
                                    std::sin(yaw) * std::cos(params.pitch_down_rad),
                                    -std::sin(params.pitch_down_rad));
      poses.push_back({t_s, lookAt(eye, eye + forward)});
    }
    return poses;
  }
  *error = "walkthrough: no path keeping " + std::to_string(c) + " m clearance found in " +
           std::to_string(params.max_attempts) + " attempts";
  return std::nullopt;
}

std::optional<std::vector<TimedPose>> makeTour(const AnalyticScene& scene, const TourParams& params,
                                               int frames, double rate_hz, uint32_t seed,
                                               std::string* error) {
  if (params.route_m.size() < 3) {
    *error = "tour: the route needs at least 3 points";
    return std::nullopt;
  }
  const DenseCurve curve = densifyCentripetal(params.route_m, kTourSamplesPerSegment);
  for (const Eigen::Vector3d& p : curve.points) {
    if (scene.clearance(p) < params.clearance_m) {
      *error = "tour: the route passes within " + std::to_string(scene.clearance(p)) +
               " m of a solid at (" + std::to_string(p.x()) + ", " + std::to_string(p.y()) + ", " +
               std::to_string(p.z()) + ")";
      return std::nullopt;
    }
  }
  std::mt19937 rng(seed);
  const double sweep_phase = uniform(&rng, 0, 2 * M_PI);
  const double nod_phase = uniform(&rng, 0, 2 * M_PI);
  std::vector<TimedPose> poses;
  poses.reserve(std::max(frames, 0));
  for (int k = 0; k < frames; ++k) {
    const double t_s = k / rate_hz;
    const double s_m = params.speed_mps * t_s;
    const Eigen::Vector3d eye = positionAt(curve, s_m);
    const Eigen::Vector3d ahead = positionAt(curve, s_m + params.heading_window_m) -
                                  positionAt(curve, s_m - params.heading_window_m);
    const double yaw =
        std::atan2(ahead.y(), ahead.x()) +
        params.sweep_amplitude_rad * std::sin(2 * M_PI * t_s / params.sweep_period_s + sweep_phase);
    const double pitch =
        params.pitch_down_rad +
        params.nod_amplitude_rad * std::sin(2 * M_PI * t_s / params.nod_period_s + nod_phase);
    const Eigen::Vector3d forward(std::cos(yaw) * std::cos(pitch), std::sin(yaw) * std::cos(pitch),
                                  -std::sin(pitch));
    poses.push_back({t_s, lookAt(eye, eye + forward)});
  }
  return poses;
}

double tourLengthM(const std::vector<Eigen::Vector3d>& route_m) {
  if (route_m.size() < 3) return 0.0;
  return densifyCentripetal(route_m, kTourSamplesPerSegment).arc_m.back();
}

int fullTourFrames(const ScenePreset& preset, double rate_hz) {
  if (preset.route_m.size() < 3) return 0;
  const double step_m = TourParams{}.speed_mps / rate_hz;
  return static_cast<int>(std::ceil(tourLengthM(preset.route_m) / step_m));
}

std::vector<std::string> trajectoryNames() { return {"orbit", "walkthrough"}; }

std::optional<std::vector<TimedPose>> makeTrajectory(const std::string& name,
                                                     const ScenePreset& preset, int frames,
                                                     double rate_hz, uint32_t seed,
                                                     std::string* error, double revolutions) {
  if (name == "orbit") {
    OrbitParams orbit;
    orbit.revolutions = revolutions;
    orbit.centre_m = preset.focus_m;
    orbit.radius_m = preset.orbit_radius_m;
    orbit.height_m = preset.orbit_height_m;
    return makeOrbit(orbit, frames, rate_hz, seed);
  }
  if (name == "walkthrough" && !preset.route_m.empty()) {
    TourParams tour;
    tour.route_m = preset.route_m;
    return makeTour(preset.scene, tour, frames, rate_hz, seed, error);
  }
  if (name == "walkthrough") {
    WalkthroughParams walk;
    walk.free_space_m = preset.room_interior;
    return makeWalkthrough(preset.scene, walk, frames, rate_hz, seed, error);
  }
  *error = "unknown trajectory '" + name + "'";
  return std::nullopt;
}

std::vector<TimedPose> addOdometryDrift(const std::vector<TimedPose>& truth, double yaw_deg,
                                        double metres) {
  std::vector<TimedPose> out = truth;
  if (truth.empty()) return out;
  const Eigen::Vector3d pivot = truth.front().T_world_camera.translation();
  for (size_t k = 0; k < truth.size(); ++k) {
    const double f = truth.size() > 1 ? static_cast<double>(k) / (truth.size() - 1) : 0.0;
    Eigen::Isometry3d D = Eigen::Isometry3d::Identity();
    D.linear() =
        Eigen::AngleAxisd(f * yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    D.translation() =
        pivot - D.linear() * pivot + f * metres * Eigen::Vector3d(2, 1, 0).normalized();
    out[k].T_world_camera = D * truth[k].T_world_camera;
  }
  return out;
}

}  // namespace stereo_fusion::sim
