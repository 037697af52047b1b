#pragma once
#include <Eigen/Geometry>
#include <optional>
#include <string>

namespace stereo_fusion {

/// How far a quaternion's norm may be off 1 and still be taken (normalised) as a rotation.
constexpr double kMaxQuaternionNormError = 0.01;

/// The rotation quaternion (x, y, z, w) stands for, normalised; nullopt with `why` when a
/// component is not finite or its norm is off 1 by more than kMaxQuaternionNormError (zero
/// included): such a pose carries no rotation, and tf2 refuses it as well.
std::optional<Eigen::Quaterniond> unitQuaternion(double x, double y, double z, double w,
                                                 std::string* why);

}  // namespace stereo_fusion
