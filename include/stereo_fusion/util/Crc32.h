#pragma once
#include <cstddef>
#include <cstdint>

namespace stereo_fusion {

/// CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320): zlib's crc32() for any size_t length.
/// Pass the previous result as `crc` to continue over several buffers; crc32("123456789") =
/// 0xCBF43926.
uint32_t crc32(const uint8_t* data, size_t size, uint32_t crc = 0);

}  // namespace stereo_fusion
