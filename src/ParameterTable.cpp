#include "stereo_fusion/ParameterTable.h"

#include <algorithm>
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

size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];  // row i-1, column j-1
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t above = row[j];
      row[j] = std::min({above + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

std::string nearestName(const std::string& name, const std::vector<std::string>& known) {
  std::string best;
  size_t best_distance = std::numeric_limits<size_t>::max();
  for (const std::string& k : known) {
    const size_t d = editDistance(name, k);
    if (d < best_distance) {
      best_distance = d;
      best = k;
    }
  }
  return best;
}

std::string unknownParameterMessage(const std::string& shown, const std::string& name,
                                    const std::vector<std::string>& known) {
  const std::string nearest = nearestName(name, known);
  return "unknown parameter '" + shown + "'" +
         (nearest.empty() ? std::string() : " (did you mean '" + nearest + "'?)");
}

}  // namespace parameter_text
}  // namespace stereo_fusion
