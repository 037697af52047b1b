#pragma once
// sensor_msgs/CompressedImage → sensor_msgs/Image, as image_transport's `compressed` and
// `compressedDepth` transports publish them (image_transport_plugins' formats). Debian ships
// image_transport without those plugins; the package's own subscriber plugins
// (CompressedSubscribers) decode with these, so a bag or driver with compressed images needs no
// republish.

#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>

#include <string>

namespace stereo_fusion {

/// The `compressed` transport: JPEG or PNG bytes, `format` "<encoding>; jpeg compressed bgr8"
/// (the original encoding before ';': colour comes back in that channel order, 16-bit PNG as
/// mono16 / 16UC1), or a bare "jpeg" / "png" (older publishers: bgr8, mono8 or mono16 by
/// the decoded channels and depth). False with a message when the bytes do not decode.
bool decodeCompressedImage(const sensor_msgs::CompressedImage& in, sensor_msgs::Image* out,
                           std::string* error);

/// The `compressedDepth` transport: `format` "16UC1; compressedDepth png" or
/// "32FC1; compressedDepth png"; `data` is a 12-byte header (int32 format, float quantisation
/// parameters a, b) followed by a 16-bit PNG. 16UC1: the PNG's values (mm). 32FC1: the PNG
/// holds quantised inverse depth q; depth = a / (q − b), and q = 0 is no measurement (NaN).
/// RVL-coded depth and anything else: false with a message.
bool decodeCompressedDepth(const sensor_msgs::CompressedImage& in, sensor_msgs::Image* out,
                           std::string* error);

}  // namespace stereo_fusion
