#include "stereo_fusion/trajectory/UnitQuaternion.h"

#include <cmath>
#include <sstream>

namespace stereo_fusion {

std::optional<Eigen::Quaterniond> unitQuaternion(double x, double y, double z, double w,
                                                 std::string* why) {
  const Eigen::Quaterniond q(w, x, y, z);
  if (!q.coeffs().allFinite()) {
    *why = "its quaternion is not finite";
    return std::nullopt;
  }
  const double norm = q.norm();
  if (std::abs(norm - 1.0) > kMaxQuaternionNormError) {
    std::ostringstream os;
    os << "its quaternion (" << x << ", " << y << ", " << z << ", " << w << ") has norm " << norm
       << ", not 1 within " << kMaxQuaternionNormError << ": it is no rotation";
    *why = os.str();
    return std::nullopt;
  }
  return q.normalized();
}

}  // namespace stereo_fusion
