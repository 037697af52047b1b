#pragma once
// The soak test behind scripts/soak.sh: an endless corridor replayed through the Mapper, the
// process' resident memory sampled as it goes, and the curves drawn into a PNG.

#include <cstddef>
#include <string>
#include <vector>

#include "stereo_fusion/MapperConfig.h"

namespace stereo_fusion::soak {

/// What to run.
struct SoakOptions {
  size_t frames = 10000;      ///< frames to fuse
  size_t sample_every = 100;  ///< frames between RSS samples
  int width_px = 160;         ///< image size of the simulated camera
  int height_px = 120;
  double speed_m_per_frame = 0.05;  ///< the camera moves along +x by this much every frame
  std::string csv_path;             ///< receives one row per sample
  MapperConfig config;
};

/// One sample.
struct SoakSample {
  size_t frame = 0;
  double rss_mb = 0;  ///< VmRSS of this process
  size_t blocks = 0;
  unsigned long long evicted = 0;  ///< blocks evicted so far
  double map_mb = 0;               ///< BlockOctree::memoryBytes()
  double mean_frame_ms = 0;        ///< mean integrate() time since the previous sample
};

/// Fuses `options.frames` frames of a corridor (floor 0.5 m below, wall 2 m ahead; both
/// infinite, so a few rendered views shifted along x are exact for any x) and samples memory.
/// Writes the CSV as it goes (a killed run keeps its samples). False with a message on error.
bool runSoak(const SoakOptions& options, std::vector<SoakSample>* samples, std::string* error);

/// Reads a CSV written by runSoak().
bool readSoakCsv(const std::string& path, std::vector<SoakSample>* samples, std::string* error);

/// Draws RSS over frames for each (label, samples) series into a PNG.
bool plotSoak(const std::vector<std::pair<std::string, std::vector<SoakSample>>>& series,
              const std::string& png_path, std::string* error);

}  // namespace stereo_fusion::soak
