#include "readers/DatasetReader.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "stereo_fusion/io/TextFile.h"

namespace stereo_fusion {

namespace fs = std::filesystem;

namespace {

bool hasExtension(const fs::path& p, std::initializer_list<const char*> extensions) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  for (const char* e : extensions)
    if (ext == e) return true;
  return false;
}

/// Regular files of `dir` with one of `extensions`, sorted by name; empty if `dir` is absent.
std::vector<std::string> listImages(const fs::path& dir,
                                    std::initializer_list<const char*> extensions) {
  std::vector<std::string> files;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return files;
  for (const auto& entry : fs::directory_iterator(dir, ec))
    if (entry.is_regular_file() && hasExtension(entry.path(), extensions))
      files.push_back(entry.path().string());
  std::sort(files.begin(), files.end());
  return files;
}

bool readCalibration(const fs::path& path, StereoCamera* camera, std::string* error) {
  std::string yaml;
  if (!readTextFile(path.string(), &yaml)) {
    *error = path.string() + ": missing (the dataset folder needs calibration.yaml)";
    return false;
  }
  // OpenCV's FileStorage writes a "%YAML:1.0" directive that YAML parsers reject.
  if (yaml.rfind("%YAML:", 0) == 0) yaml = yaml.substr(yaml.find('\n') + 1);
  YAML::Node root;
  try {
    root = YAML::Load(yaml);
  } catch (const YAML::Exception& e) {
    *error = path.string() + ": not valid YAML: " + e.what();
    return false;
  }
  if (!root.IsMap()) {
    *error = path.string() + ": expected keys width, height, fx, fy, cx, cy, baseline";
    return false;
  }
  double values[7];
  const char* keys[7] = {"width", "height", "fx", "fy", "cx", "cy", "baseline"};
  for (int k = 0; k < 7; ++k) {
    const YAML::Node node = root[keys[k]];
    if (!node || !node.IsScalar()) {
      *error = path.string() + ": missing key '" + keys[k] + "'";
      return false;
    }
    try {
      values[k] = node.as<double>();
    } catch (const YAML::Exception&) {
      *error = path.string() + ":" + std::to_string(node.Mark().line + 1) + ": '" + keys[k] +
               "' is not a number: " + node.Scalar();
      return false;
    }
  }
  if (values[0] != std::floor(values[0]) || values[1] != std::floor(values[1]) ||
      !(values[0] > 0) || !(values[1] > 0) || values[0] > 1e5 || values[1] > 1e5) {
    *error = path.string() + ": width and height must be whole pixel counts in [1, 100000]";
    return false;
  }
  std::string why;
  auto created = StereoCamera::create(static_cast<int>(values[0]), static_cast<int>(values[1]),
                                      values[2], values[3], values[4], values[5], values[6], &why);
  if (!created) {
    *error = path.string() + ": " + why;
    return false;
  }
  *camera = *created;
  return true;
}

bool readPoses(const fs::path& path, std::vector<DatasetFrameInfo>* frames, std::string* error) {
  if (!fs::exists(path)) {
    *error = path.string() + ": missing (the dataset folder needs poses.txt)";
    return false;
  }
  return readTumPoses(path.string(), frames, error);
}

/// cv::imread, with the one message every caller gives when the file cannot be decoded.
cv::Mat readImage(const std::string& path, int flags, std::string* error) {
  cv::Mat image;
  try {
    image = cv::imread(path, flags);
  } catch (const cv::Exception&) {
    // Some decoders throw instead of returning nothing, e.g. a PFM header with width 0 in a
    // file named .png (imread goes by content); found by fuzz_dataset_folder.
    image.release();
  }
  if (image.empty()) *error = path + ": unreadable or truncated image";
  return image;
}

cv::Mat readDisparity(const std::string& path, std::string* error) {
  if (hasExtension(path, {".pfm"})) {
    cv::Mat pfm = readPfm(path, error);
    if (pfm.empty()) return pfm;
    cv::Mat disparity = pfm.clone();
    for (int v = 0; v < disparity.rows; ++v) {
      float* row = disparity.ptr<float>(v);
      for (int u = 0; u < disparity.cols; ++u)
        if (!std::isfinite(row[u]) || row[u] <= 0.0f) row[u] = 0.0f;
    }
    return disparity;
  }
  const cv::Mat raw = readImage(path, cv::IMREAD_UNCHANGED, error);
  if (raw.empty()) return {};
  if (raw.type() != CV_16UC1) {
    *error = path + ": disparity PNG must be 16-bit single channel (KITTI: value / 256)";
    return {};
  }
  cv::Mat disparity;
  raw.convertTo(disparity, CV_32FC1, 1.0 / 256.0);  // 0 stays 0 = invalid
  return disparity;
}

cv::Mat readColor(const std::string& path, std::string* error) {
  const cv::Mat raw = readImage(path, cv::IMREAD_UNCHANGED, error);
  if (raw.empty()) return {};
  if (raw.depth() != CV_8U) {
    *error = path + ": colour image must be 8-bit";
    return {};
  }
  cv::Mat rgb;
  switch (raw.channels()) {
    case 1: return raw;
    case 3: cv::cvtColor(raw, rgb, cv::COLOR_BGR2RGB); return rgb;
    case 4: cv::cvtColor(raw, rgb, cv::COLOR_BGRA2RGB); return rgb;
    default:
      *error = path + ": unsupported channel count " + std::to_string(raw.channels());
      return {};
  }
}

}  // namespace

bool readTumPoses(const std::string& file, std::vector<DatasetFrameInfo>* frames,
                  std::string* error) {
  const fs::path path(file);
  std::ifstream in(path);
  if (!in) {
    *error = path.string() + ": cannot be opened";
    return false;
  }
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream fields(line);
    double v[8];
    int n = 0;
    std::string token;
    bool numeric = true;
    while (fields >> token) {
      if (n == 8) {
        n = 9;
        break;
      }
      try {
        size_t used = 0;
        v[n] = std::stod(token, &used);
        numeric &= used == token.size();
      } catch (...) {
        numeric = false;
      }
      ++n;
    }
    const std::string where = path.string() + ":" + std::to_string(line_number);
    if (n != 8 || !numeric) {
      *error = where + ": expected 8 numbers 'timestamp tx ty tz qx qy qz qw'";
      return false;
    }
    // A malformed line is a broken file (an error); a well-formed line with an unusable pose
    // (a SLAM export's NaN, a zero quaternion) costs only its frame, as in the nodelet.
    DatasetFrameInfo info;
    info.index = frames->size();
    info.timestamp_s = v[0];
    info.T_world_camera = Eigen::Isometry3d::Identity();
    const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);  // file order qx qy qz qw
    bool finite = true;
    for (double x : v) finite = finite && std::isfinite(x);
    if (!finite)
      info.pose_error = where + ": pose is not finite";
    else if (std::abs(q.norm() - 1.0) > 1e-3)
      info.pose_error =
          where + ": quaternion is not unit length (|q| = " + std::to_string(q.norm()) + ")";
    else {
      info.T_world_camera.linear() = q.normalized().toRotationMatrix();
      info.T_world_camera.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    }
    frames->push_back(info);
  }
  return true;
}

std::optional<DatasetReader> DatasetReader::open(const std::string& folder, std::string* error,
                                                 const SgbmParams& sgbm) {
  const fs::path root(folder);
  std::error_code ec;
  if (!fs::is_directory(root, ec)) {
    *error = folder + ": not a dataset folder (no such directory)";
    return std::nullopt;
  }
  DatasetReader reader;
  reader.folder_ = folder;
  reader.sgbm_ = sgbm;
  if (!readCalibration(root / "calibration.yaml", &reader.camera_, error)) return std::nullopt;
  if (!readPoses(root / "poses.txt", &reader.frames_, error)) return std::nullopt;

  const auto disparities = listImages(root / "disparity", {".png", ".pfm"});
  const auto colors = listImages(root / "color", {".png", ".jpg", ".jpeg"});
  const auto rights = listImages(root / "right", {".png", ".jpg", ".jpeg"});
  size_t count = disparities.size();
  if (disparities.empty()) {
    if (rights.empty()) {
      *error = folder + ": no disparity/ images and no right/ images to compute disparity from";
      return std::nullopt;
    }
    if (colors.size() != rights.size()) {
      *error = folder +
               ": computing disparity needs one color/ (left) image per right/ image, found " +
               std::to_string(colors.size()) + " and " + std::to_string(rights.size());
      return std::nullopt;
    }
    // OpenCV's SGBM needs more columns than disparities: on a narrower image it asks for a
    // negative-sized buffer or throws from a destructor (std::terminate), found by fuzzing.
    if (reader.camera_.width() <= sgbm.num_disparities) {
      *error = (root / "calibration.yaml").string() + ": images " +
               std::to_string(reader.camera_.width()) +
               " px wide are too narrow to compute disparity with SGBM (" +
               std::to_string(sgbm.num_disparities) + " disparities need a wider image)";
      return std::nullopt;
    }
    reader.uses_sgbm_ = true;
    count = rights.size();
  }
  if (!colors.empty() && colors.size() != count) {
    *error = folder + ": color/ has " + std::to_string(colors.size()) + " images but there are " +
             std::to_string(count) + " frames";
    return std::nullopt;
  }
  if (reader.frames_.size() < count) {
    *error = (root / "poses.txt").string() + ": " + std::to_string(reader.frames_.size()) +
             " poses for " + std::to_string(count) + " frames";
    return std::nullopt;
  }
  reader.frames_.resize(count);  // extra pose lines (e.g. a longer trajectory) are ignored
  for (size_t i = 0; i < count; ++i) {
    DatasetFrameInfo& f = reader.frames_[i];
    if (!disparities.empty()) f.disparity_path = disparities[i];
    if (!colors.empty()) f.color_path = colors[i];
    if (!rights.empty() && i < rights.size()) f.right_path = rights[i];
  }
  if (fs::is_regular_file(root / "gt_mesh.ply", ec))
    reader.gt_mesh_path_ = (root / "gt_mesh.ply").string();
  return reader;
}

bool DatasetReader::load(size_t i, StereoFrame* frame, std::string* error) const {
  if (i >= frames_.size()) {
    *error = "frame " + std::to_string(i) + " is out of range";
    return false;
  }
  const DatasetFrameInfo& info = frames_[i];
  if (!info.pose_error.empty()) {
    *error = "frame " + std::to_string(i) + ": " + info.pose_error;
    return false;
  }
  StereoFrame out;
  out.timestamp_s = info.timestamp_s;
  out.T_world_camera = info.T_world_camera;
  out.camera = camera_;
  const cv::Size expected(camera_.width(), camera_.height());
  if (!info.color_path.empty()) {
    out.color = readColor(info.color_path, error);
    if (out.color.empty()) return false;
    if (out.color.size() != expected) {
      *error = info.color_path + ": image is " + std::to_string(out.color.cols) + "x" +
               std::to_string(out.color.rows) + " but calibration.yaml says " +
               std::to_string(expected.width) + "x" + std::to_string(expected.height);
      return false;
    }
  }
  if (uses_sgbm_) {
    const cv::Mat right = readImage(info.right_path, cv::IMREAD_GRAYSCALE, error);
    if (right.empty()) return false;
    if (right.size() != expected) {
      *error = info.right_path + ": right image size differs from calibration.yaml";
      return false;
    }
    cv::Mat left;
    if (out.color.channels() == 3)
      cv::cvtColor(out.color, left, cv::COLOR_RGB2GRAY);
    else
      left = out.color;
    const int block = sgbm_.block_size;
    auto matcher = cv::StereoSGBM::create(0, sgbm_.num_disparities, block, 8 * block * block,
                                          32 * block * block, 1, 63, sgbm_.uniqueness_ratio,
                                          sgbm_.speckle_window_size, sgbm_.speckle_range,
                                          cv::StereoSGBM::MODE_SGBM_3WAY);
    cv::Mat fixed_point;
    matcher->compute(left, right, fixed_point);
    fixed_point.convertTo(out.disparity_px, CV_32FC1, 1.0 / 16.0);  // SGBM gives 1/16 px
    cv::threshold(out.disparity_px, out.disparity_px, 0.0, 0.0, cv::THRESH_TOZERO);
  } else {
    out.disparity_px = readDisparity(info.disparity_path, error);
    if (out.disparity_px.empty()) return false;
    if (out.disparity_px.size() != expected) {
      *error = info.disparity_path + ": disparity is " + std::to_string(out.disparity_px.cols) +
               "x" + std::to_string(out.disparity_px.rows) + " but calibration.yaml says " +
               std::to_string(expected.width) + "x" + std::to_string(expected.height);
      return false;
    }
  }
  *frame = std::move(out);
  return true;
}

cv::Mat readPfm(const std::string& path, std::string* error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *error = path + ": cannot open";
    return {};
  }
  std::string magic;
  long width = 0, height = 0;
  double scale = 0.0;
  if (!(in >> magic >> width >> height >> scale) || (magic != "Pf" && magic != "PF")) {
    *error = path + ": not a PFM file (bad header)";
    return {};
  }
  in.get();  // the single whitespace byte ending the header
  const int channels = magic == "PF" ? 3 : 1;
  if (width <= 0 || height <= 0 || width > 100000 || height > 100000 || scale == 0.0 ||
      !std::isfinite(scale)) {
    *error = path + ": PFM header has an invalid size or scale";
    return {};
  }
  const size_t count = static_cast<size_t>(width) * height * channels;
  // Check the file really holds the data before allocating: a corrupt header must not ask for
  // 100 GB.
  const std::streampos data_start = in.tellg();
  in.seekg(0, std::ios::end);
  const std::streamoff available = in.tellg() - data_start;
  in.seekg(data_start);
  if (available < 0 || static_cast<size_t>(available) < count * sizeof(float)) {
    *error = path + ": truncated PFM (expected " + std::to_string(count * sizeof(float)) +
             " data bytes)";
    return {};
  }
  std::vector<float> data(count);
  in.read(reinterpret_cast<char*>(data.data()),
          static_cast<std::streamsize>(count * sizeof(float)));
  if (static_cast<size_t>(in.gcount()) != count * sizeof(float)) {
    *error = path + ": truncated PFM (expected " + std::to_string(count * sizeof(float)) +
             " data bytes)";
    return {};
  }
  const bool file_little_endian = scale < 0.0;
  const uint16_t probe = 1;
  const bool host_little_endian = *reinterpret_cast<const uint8_t*>(&probe) == 1;
  if (file_little_endian != host_little_endian)
    for (float& f : data) {
      uint32_t bits;
      std::memcpy(&bits, &f, 4);
      bits = __builtin_bswap32(bits);
      std::memcpy(&f, &bits, 4);
    }
  cv::Mat image(static_cast<int>(height), static_cast<int>(width), CV_32FC1);
  for (int v = 0; v < image.rows; ++v) {
    const float* src = data.data() + static_cast<size_t>(image.rows - 1 - v) * width * channels;
    float* dst = image.ptr<float>(v);
    for (int u = 0; u < image.cols; ++u) dst[u] = src[u * channels];  // first channel
  }
  return image;
}

bool writePfm(const std::string& path, const cv::Mat& image, std::string* error) {
  if (image.type() != CV_32FC1) {
    *error = path + ": writePfm needs a CV_32FC1 image";
    return false;
  }
  std::ofstream out(path, std::ios::binary);
  if (!out) {
    *error = path + ": cannot open for writing";
    return false;
  }
  out << "Pf\n" << image.cols << " " << image.rows << "\n-1\n";  // negative scale: little-endian
  for (int v = image.rows - 1; v >= 0; --v)
    out.write(reinterpret_cast<const char*>(image.ptr<float>(v)), image.cols * sizeof(float));
  if (!out) {
    *error = path + ": write failed";
    return false;
  }
  return true;
}

}  // namespace stereo_fusion
