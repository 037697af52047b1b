#pragma once
#include <fstream>
#include <sstream>
#include <string>

namespace stereo_fusion {

/// Reads a whole text file; false when it cannot be opened.
inline bool readTextFile(const std::string& path, std::string* text) {
  std::ifstream in(path);
  if (!in) return false;
  std::stringstream buffer;
  buffer << in.rdbuf();
  *text = buffer.str();
  return true;
}

}  // namespace stereo_fusion
