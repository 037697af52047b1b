#include "stereo_fusion/ParameterTable.h"

#include <cctype>
#include <cstdlib>
#include <limits>
#include <sstream>

namespace stereo_fusion {
namespace parameter_text {

std::string formatDouble(double v) {
  std::ostringstream os;
  os.precision(std::numeric_limits<double>::max_digits10);
  os << v;
  // Print 0.02 rather than 0.020000000000000000416 when the short form round-trips.
  std::ostringstream shortest;
  shortest << v;
  // strtod, not stod: stod throws for subnormal values that are valid doubles.
  return std::strtod(shortest.str().c_str(), nullptr) == v ? shortest.str() : os.str();
}

bool parseDouble(const std::string& text, double* out) {
  if (text.empty() || std::isspace(static_cast<unsigned char>(text[0]))) return false;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);  // subnormals parse (stod would throw)
  if (end != text.c_str() + text.size()) return false;
  *out = v;
  return true;
}

bool parseInt(const std::string& text, int* out) {
  try {
    size_t used = 0;
    const long v = std::stol(text, &used);
    if (used != text.size() || v < std::numeric_limits<int>::min() ||
        v > std::numeric_limits<int>::max())
      return false;
    *out = static_cast<int>(v);
    return true;
  } catch (...) {
    return false;
  }
}

}  // namespace parameter_text
}  // namespace stereo_fusion
