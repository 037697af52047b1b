#include "soak/SoakRun.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "simulator/AnalyticScene.h"
#include "stereo_fusion/Mapper.h"
#include "stereo_fusion/util/ProcessMemory.h"
#include "stereo_fusion/util/Timer.h"

namespace stereo_fusion::soak {

bool runSoak(const SoakOptions& options, std::vector<SoakSample>* samples, std::string* error) {
  std::string why;
  const double f_px = 0.82 * options.width_px;  // ~63° horizontal field of view
  auto camera =
      StereoCamera::create(options.width_px, options.height_px, f_px, f_px,
                           (options.width_px - 1) / 2.0, (options.height_px - 1) / 2.0, 0.1, &why);
  if (!camera) {
    *error = why;
    return false;
  }
  sim::AnalyticScene corridor;
  corridor.add(sim::makePlane({0, 0.5, 0}, {0, -1, 0}), {180, 160, 120});
  corridor.add(sim::makePlane({0, 0, 2.0}, {0, 0, -1}), {90, 120, 200});
  // A few views with different pitch and yaw, rendered once: the corridor is the same at any x,
  // so view k shifted to x = speed · frame is the exact image of that pose.
  std::vector<StereoFrame> views;
  for (int k = 0; k < 8; ++k) {
    const double yaw = 0.25 * std::sin(k * 0.8), pitch = 0.15 * std::cos(k * 1.3);
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()) *
                  Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitX()))
                     .toRotationMatrix();
    StereoFrame frame;
    frame.camera = *camera;
    frame.T_world_camera = T;
    cv::Mat depth;
    sim::renderDepthAndColor(corridor, *camera, T, &depth, &frame.color);
    frame.disparity_px = sim::disparityFromDepth(depth, *camera);
    views.push_back(frame);
  }
  std::ofstream csv(options.csv_path);
  if (!csv) {
    *error = options.csv_path + ": cannot write";
    return false;
  }
  csv << "frame,rss_mb,blocks,evicted,map_mb,mean_frame_ms\n";
  Mapper mapper(options.config);
  double window_ms = 0;
  size_t window_frames = 0;
  auto sample = [&](size_t frame) {
    SoakSample s;
    s.frame = frame;
    s.rss_mb = readProcessMemory().resident_mb;
    s.blocks = mapper.tsdf().blockCount();
    s.evicted = mapper.blocksEvicted();
    s.map_mb = mapper.tsdf().memoryBytes() / 1048576.0;
    s.mean_frame_ms = window_frames ? window_ms / window_frames : 0.0;
    window_ms = 0;
    window_frames = 0;
    samples->push_back(s);
    csv << s.frame << "," << s.rss_mb << "," << s.blocks << "," << s.evicted << "," << s.map_mb
        << "," << s.mean_frame_ms << "\n"
        << std::flush;
  };
  sample(0);
  for (size_t i = 0; i < options.frames; ++i) {
    StereoFrame frame = views[i % views.size()];
    frame.T_world_camera.translation().x() = options.speed_m_per_frame * i;
    frame.timestamp_s = 0.1 * (i + 1);
    Timer timer;
    const IntegrationResult r = mapper.integrate(frame);
    window_ms += timer.elapsedMs();
    ++window_frames;
    if (!r.accepted) {
      *error = "frame " + std::to_string(i) + " rejected: " + r.error;
      return false;
    }
    if ((i + 1) % options.sample_every == 0 || i + 1 == options.frames) sample(i + 1);
  }
  return true;
}

bool readSoakCsv(const std::string& path, std::vector<SoakSample>* samples, std::string* error) {
  std::ifstream in(path);
  if (!in) {
    *error = path + ": cannot open";
    return false;
  }
  std::string line;
  std::getline(in, line);  // header
  size_t n = 1;
  while (std::getline(in, line)) {
    ++n;
    SoakSample s;
    char c1, c2, c3, c4, c5;
    std::istringstream row(line);
    if (!(row >> s.frame >> c1 >> s.rss_mb >> c2 >> s.blocks >> c3 >> s.evicted >> c4 >> s.map_mb >>
          c5 >> s.mean_frame_ms)) {
      *error = path + ":" + std::to_string(n) + ": malformed row";
      return false;
    }
    samples->push_back(s);
  }
  return true;
}

bool plotSoak(const std::vector<std::pair<std::string, std::vector<SoakSample>>>& series,
              const std::string& png_path, std::string* error) {
  const int width = 960, height = 540, left = 80, right = 30, top = 50, bottom = 60;
  cv::Mat img(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  double max_frame = 1, max_rss = 1;
  for (const auto& [label, samples] : series)
    for (const SoakSample& s : samples) {
      max_frame = std::max(max_frame, static_cast<double>(s.frame));
      max_rss = std::max(max_rss, s.rss_mb);
    }
  // Round the axis up to a "nice" step.
  const double raw_step = max_rss / 5;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw_step)));
  const double step = std::ceil(raw_step / magnitude) * magnitude;
  const double top_rss = step * std::ceil(max_rss / step);
  auto toPixel = [&](double frame, double rss) {
    return cv::Point(left + static_cast<int>((width - left - right) * frame / max_frame),
                     height - bottom - static_cast<int>((height - top - bottom) * rss / top_rss));
  };
  const cv::Scalar grey(200, 200, 200), black(0, 0, 0);
  for (double r = 0; r <= top_rss + 1e-9; r += step) {
    cv::line(img, toPixel(0, r), toPixel(max_frame, r), grey, 1);
    cv::putText(img, std::to_string(static_cast<long>(std::lround(r))),
                toPixel(0, r) + cv::Point(-60, 5), cv::FONT_HERSHEY_SIMPLEX, 0.45, black, 1,
                cv::LINE_AA);
  }
  for (int k = 0; k <= 5; ++k) {
    const double f = max_frame * k / 5;
    cv::line(img, toPixel(f, 0), toPixel(f, 0) + cv::Point(0, 5), black, 1);
    cv::putText(img, std::to_string(static_cast<long>(std::lround(f))),
                toPixel(f, 0) + cv::Point(-20, 22), cv::FONT_HERSHEY_SIMPLEX, 0.45, black, 1,
                cv::LINE_AA);
  }
  cv::line(img, toPixel(0, 0), toPixel(max_frame, 0), black, 1);
  cv::line(img, toPixel(0, 0), toPixel(0, top_rss), black, 1);
  cv::putText(img, "frames", cv::Point(width / 2 - 30, height - 15), cv::FONT_HERSHEY_SIMPLEX, 0.55,
              black, 1, cv::LINE_AA);
  cv::putText(img, "RSS (MiB)", cv::Point(10, top - 15), cv::FONT_HERSHEY_SIMPLEX, 0.55, black, 1,
              cv::LINE_AA);
  cv::putText(img, "stereo_fusion soak: resident memory", cv::Point(width / 2 - 170, 25),
              cv::FONT_HERSHEY_SIMPLEX, 0.65, black, 1, cv::LINE_AA);
  const cv::Scalar colours[] = {cv::Scalar(40, 40, 220), cv::Scalar(200, 120, 20),
                                cv::Scalar(40, 160, 40)};
  for (size_t k = 0; k < series.size(); ++k) {
    std::vector<cv::Point> line;
    for (const SoakSample& s : series[k].second) line.push_back(toPixel(s.frame, s.rss_mb));
    const cv::Scalar colour = colours[k % 3];
    if (line.size() >= 2) cv::polylines(img, line, false, colour, 2, cv::LINE_AA);
    const cv::Point key(left + 20, top + 20 + 22 * static_cast<int>(k));
    cv::line(img, key, key + cv::Point(30, 0), colour, 3);
    cv::putText(img, series[k].first, key + cv::Point(40, 5), cv::FONT_HERSHEY_SIMPLEX, 0.5, black,
                1, cv::LINE_AA);
  }
  if (!cv::imwrite(png_path, img)) {
    *error = png_path + ": cannot write the PNG";
    return false;
  }
  return true;
}

}  // namespace stereo_fusion::soak
