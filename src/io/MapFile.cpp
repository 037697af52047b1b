#include "stereo_fusion/io/MapFile.h"

#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstddef>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <new>
#include <sstream>

#include "stereo_fusion/util/Crc32.h"

namespace stereo_fusion {

namespace {

constexpr char kMagic[8] = {'S', 'F', 'U', 'S', 'E', 'M', 'A', 'P'};

// Explicit little-endian encoding: the file must read the same on any host.
void storeU32(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}
void storeU64(uint8_t* p, uint64_t v) {
  for (int i = 0; i < 8; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}
void storeF32(uint8_t* p, float v) {
  uint32_t bits;
  std::memcpy(&bits, &v, 4);
  storeU32(p, bits);
}
void storeF64(uint8_t* p, double v) {
  uint64_t bits;
  std::memcpy(&bits, &v, 8);
  storeU64(p, bits);
}
uint32_t getU32(const uint8_t* p) {
  uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= uint32_t{p[i]} << (8 * i);
  return v;
}
uint64_t getU64(const uint8_t* p) {
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= uint64_t{p[i]} << (8 * i);
  return v;
}
float getF32(const uint8_t* p) {
  const uint32_t bits = getU32(p);
  float v;
  std::memcpy(&v, &bits, 4);
  return v;
}
double getF64(const uint8_t* p) {
  const uint64_t bits = getU64(p);
  double v;
  std::memcpy(&v, &bits, 8);
  return v;
}

// A voxel's 12 file bytes are f32 sdf, f32 weight, u8 r, g, b, reserved, little-endian: the
// in-memory Voxel itself on a little-endian host, where whole blocks are copied at memory speed
// (the map is locked while it is encoded).
constexpr bool kVoxelIsFileRecord = __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__;
static_assert(sizeof(Voxel) == 12 && offsetof(Voxel, weight) == 4 && offsetof(Voxel, r) == 8 &&
                  offsetof(Voxel, g) == 9 && offsetof(Voxel, b) == 10 &&
                  offsetof(Voxel, reserved) == 11,
              "the map file's voxel record is the Voxel's layout");
constexpr size_t kVoxelRecordBytes = 12;

void storeVoxels(const Voxel* voxels, int count, uint8_t* out) {
  if (kVoxelIsFileRecord) {
    std::memcpy(out, voxels, count * kVoxelRecordBytes);
    return;
  }
  for (int n = 0; n < count; ++n, out += kVoxelRecordBytes) {
    const Voxel& v = voxels[n];
    storeF32(out, v.sdf_m);
    storeF32(out + 4, v.weight);
    out[8] = v.r, out[9] = v.g, out[10] = v.b, out[11] = v.reserved;
  }
}

void loadVoxels(const uint8_t* in, int count, Voxel* voxels) {
  if (kVoxelIsFileRecord) {
    std::memcpy(voxels, in, count * kVoxelRecordBytes);
    return;
  }
  for (int n = 0; n < count; ++n, in += kVoxelRecordBytes) {
    Voxel& v = voxels[n];
    v.sdf_m = getF32(in);
    v.weight = getF32(in + 4);
    v.r = in[8], v.g = in[9], v.b = in[10], v.reserved = in[11];
  }
}

/// Bit l set: level l of the block is stored (allocated).
uint8_t levelMask(const VoxelBlock& block) {
  uint8_t mask = 0;
  for (int l = 0; l < kNumLevels; ++l) mask |= static_cast<uint8_t>(block.hasLevel(l) << l);
  return mask;
}

size_t levelBytes(uint8_t mask) {
  size_t bytes = 0;
  for (int l = 0; l < kNumLevels; ++l)
    if (mask & (1u << l)) bytes += levelVoxelCount(l) * kVoxelRecordBytes;
  return bytes;
}

std::string number(double v) {
  std::ostringstream os;
  os.precision(17);
  os << v;
  return os.str();
}

}  // namespace

std::vector<uint8_t> encodeMapFile(const BlockOctree& map, const MapperConfig& config,
                                   uint64_t frames_integrated,
                                   const LastUpdateFrameOf& last_update_frame,
                                   const SeenFreeSpace& free_space) {
  std::vector<uint8_t> file =
      encodeMapFileUnsealed(map, config, frames_integrated, last_update_frame, free_space);
  sealMapFile(&file);
  return file;
}

std::vector<uint8_t> encodeMapFileUnsealed(const BlockOctree& map, const MapperConfig& config,
                                           uint64_t frames_integrated,
                                           const LastUpdateFrameOf& last_update_frame,
                                           const SeenFreeSpace& free_space) {
  const std::vector<VoxelBlock*> sorted = map.blocksSortedByKey();
  return encodeMapFileUnsealed(std::vector<const VoxelBlock*>(sorted.begin(), sorted.end()), config,
                               frames_integrated, last_update_frame, free_space);
}

size_t mapFileRecordBytes(const VoxelBlock& block) {
  return kMapFileRecordHeadBytes + levelBytes(levelMask(block));
}

size_t mapFileFreeSpaceBytes(const SeenFreeSpace& free_space) {
  return 16 + free_space.blocks.size() * kMapFileFreeSpaceRecordBytes;
}

void encodeMapFileRecord(const VoxelBlock& block, uint64_t last_update_frame, uint8_t* record) {
  storeU32(record, static_cast<uint32_t>(block.key.x));
  storeU32(record + 4, static_cast<uint32_t>(block.key.y));
  storeU32(record + 8, static_cast<uint32_t>(block.key.z));
  storeU64(record + 12, last_update_frame);
  record[20] = levelMask(block);
  record[21] = record[22] = record[23] = 0;
  record += kMapFileRecordHeadBytes;
  for (int l = 0; l < kNumLevels; ++l) {
    if (!block.hasLevel(l)) continue;
    storeVoxels(block.level(l), levelVoxelCount(l), record);
    record += levelVoxelCount(l) * kVoxelRecordBytes;
  }
}

void encodeMapFileFreeSpace(const SeenFreeSpace& free_space, uint8_t* record) {
  storeF64(record, free_space.cell_m);
  storeU64(record + 8, free_space.blocks.size());
  record += 16;
  for (const auto& [key, bits] : free_space.blocks) {
    storeU32(record, static_cast<uint32_t>(key.x));
    storeU32(record + 4, static_cast<uint32_t>(key.y));
    storeU32(record + 8, static_cast<uint32_t>(key.z));
    storeU32(record + 12, 0);
    for (size_t w = 0; w < bits.size(); ++w) storeU64(record + 16 + 8 * w, bits[w]);
    record += kMapFileFreeSpaceRecordBytes;
  }
}

void encodeMapFileHeader(const MapperConfig& config, uint64_t frames_integrated,
                         uint64_t block_count, uint64_t payload_bytes, uint8_t* header) {
  std::memcpy(header, kMagic, 8);
  storeU32(header + 8, kMapFileVersion);
  storeU32(header + 12, static_cast<uint32_t>(kMapFileHeaderBytes));
  storeF64(header + 16, config.voxel_size_m);
  storeF64(header + 24, config.truncation_vox);
  storeF64(header + 32, config.levels.scale2_min_depth_m);
  storeF64(header + 40, config.levels.scale4_min_depth_m);
  storeU64(header + 48, frames_integrated);
  storeU64(header + 56, block_count);
  storeU64(header + 64, payload_bytes);
  storeU32(header + 72, 0);
  storeU32(header + 76, 0);
}

void sealMapFileHeader(uint8_t* header, uint32_t payload_crc) {
  storeU32(header + 72, payload_crc);
  storeU32(header + 76, crc32(header, 76));
}

std::vector<uint8_t> encodeMapFileUnsealed(const std::vector<const VoxelBlock*>& blocks,
                                           const MapperConfig& config, uint64_t frames_integrated,
                                           const LastUpdateFrameOf& last_update_frame,
                                           const SeenFreeSpace& free_space) {
  static_assert(kMapFileV1RecordBytes ==
                    kMapFileRecordHeadBytes + VoxelBlock::kVoxelCount * kVoxelRecordBytes,
                "record layout");
  size_t payload_bytes = mapFileFreeSpaceBytes(free_space);
  for (const VoxelBlock* b : blocks) payload_bytes += mapFileRecordBytes(*b);
  std::vector<uint8_t> file(kMapFileHeaderBytes + payload_bytes);
  uint8_t* record = file.data() + kMapFileHeaderBytes;
  for (const VoxelBlock* b : blocks) {
    encodeMapFileRecord(*b, last_update_frame ? last_update_frame(*b) : 0, record);
    record += mapFileRecordBytes(*b);
  }
  encodeMapFileFreeSpace(free_space, record);
  encodeMapFileHeader(config, frames_integrated, blocks.size(), payload_bytes, file.data());
  return file;  // checksums at 72 and 76 still zero
}

void sealMapFile(std::vector<uint8_t>* file) {
  if (file->size() < kMapFileHeaderBytes)
    return;  // not from encodeMapFileUnsealed(): nothing to seal
  sealMapFileHeader(file->data(),
                    crc32(file->data() + kMapFileHeaderBytes, file->size() - kMapFileHeaderBytes));
}

namespace {

/// The header of a map file: `data` holds its first `available` bytes, the whole file has
/// `file_size`. Checks magic, version, the header checksum and the sizes it announces against
/// `file_size`, so a reader can refuse a file before reading its payload; fills `info` (not its
/// last update frames) and `*header_bytes`.
bool decodeMapHeader(const uint8_t* data, size_t available, size_t file_size, MapFileInfo* info,
                     size_t* header_bytes_out, std::string* error) {
  if (available < 8 || std::memcmp(data, kMagic, 8) != 0) {
    *error = "not a stereo_fusion map file (bad magic)";
    return false;
  }
  if (available < 12) {
    *error = "truncated map file: " + std::to_string(file_size) + " bytes, the header alone has " +
             std::to_string(kMapFileHeaderBytes);
    return false;
  }
  // The version comes first, so a newer file is named as such whatever its layout.
  info->version = getU32(data + 8);
  if (info->version < 1 || info->version > kMapFileVersion) {
    *error = "map file version " + std::to_string(info->version) +
             " is not supported (this build reads versions 1 to " +
             std::to_string(kMapFileVersion) + ")";
    return false;
  }
  const bool v1 = info->version == 1;
  // Where the header of this version keeps its size and checksums.
  const size_t header_bytes = v1 ? kMapFileV1HeaderBytes : kMapFileHeaderBytes;
  const size_t header_crc_at = v1 ? 68 : 76;
  if (available < header_bytes) {
    *error = "truncated map file: " + std::to_string(file_size) + " bytes, the header alone has " +
             std::to_string(header_bytes);
    return false;
  }
  if (getU32(data + header_crc_at) != crc32(data, header_crc_at) ||
      getU32(data + 12) != header_bytes) {
    *error = "corrupted map file: header checksum mismatch";
    return false;
  }
  info->voxel_size_m = getF64(data + 16);
  info->truncation_vox = getF64(data + 24);
  info->scale2_min_depth_m = getF64(data + 32);
  info->scale4_min_depth_m = getF64(data + 40);
  info->frames_integrated = getU64(data + 48);
  info->block_count = getU64(data + 56);
  const size_t payload_bytes = file_size - header_bytes;
  // The sizes the header announces, compared by division: a corrupted count must not overflow.
  // Version 1 records have one size; version 2 gives the payload's size (records are checked
  // against it one by one when decoded).
  const uint64_t announced_payload_bytes = v1 ? 0 : getU64(data + 64);
  const bool short_file = v1 ? info->block_count > payload_bytes / kMapFileV1RecordBytes
                             : announced_payload_bytes > payload_bytes;
  const bool wrong_size = v1 ? payload_bytes != info->block_count * kMapFileV1RecordBytes
                             : announced_payload_bytes != payload_bytes ||
                                   info->block_count > payload_bytes / kMapFileRecordHeadBytes;
  if (short_file || wrong_size) {
    *error = std::string(short_file ? "truncated" : "corrupted") +
             " map file: " + std::to_string(file_size) + " bytes, but the header announces " +
             std::to_string(info->block_count) + " blocks in " +
             (v1 ? std::to_string(info->block_count) + " × " + std::to_string(kMapFileV1RecordBytes)
                 : std::to_string(announced_payload_bytes)) +
             " bytes after a header of " + std::to_string(header_bytes);
    return false;
  }
  *header_bytes_out = header_bytes;
  return true;
}

}  // namespace

namespace {
/// The seen-free section at `*r` (version 3): checked (a finite cell edge ≥ 0, records that fit,
/// keys in range, sorted and unique, only bits of cells), `*r` moved past it.
bool decodeFreeSpace(const uint8_t** r, const uint8_t* end, SeenFreeSpace* out,
                     std::string* error) {
  if (end - *r < 16) {
    *error = "invalid map file: the seen-free section runs past the end of the file";
    return false;
  }
  out->cell_m = getF64(*r);
  const uint64_t count = getU64(*r + 8);
  *r += 16;
  if (!std::isfinite(out->cell_m) || out->cell_m < 0.0 || (out->cell_m == 0.0 && count != 0)) {
    *error = "invalid map file: seen-free cell edge " + number(out->cell_m);
    return false;
  }
  if (count > static_cast<uint64_t>(end - *r) / kMapFileFreeSpaceRecordBytes) {
    *error = "invalid map file: " + std::to_string(count) +
             " seen-free blocks run past the end of the file";
    return false;
  }
  out->blocks.reserve(count);
  for (uint64_t n = 0; n < count; ++n) {
    const BlockKey key{static_cast<int32_t>(getU32(*r)), static_cast<int32_t>(getU32(*r + 4)),
                       static_cast<int32_t>(getU32(*r + 8))};
    PlanningBlock::Bits bits;
    for (size_t w = 0; w < bits.size(); ++w) bits[w] = getU64(*r + 16 + 8 * w);
    const bool ordered = out->blocks.empty() || out->blocks.back().first < key;
    if (!planningBlockKeyInRange(key)) {
      *error = "invalid map file: seen-free block " + std::to_string(n) + " (" +
               std::to_string(key.x) + ", " + std::to_string(key.y) + ", " + std::to_string(key.z) +
               ") is beyond the planning grid's range (±" +
               std::to_string(kPlanningCellLimit / PlanningBlock::kSide) + " blocks)";
      return false;
    }
    if (getU32(*r + 12) != 0 || !ordered) {
      *error =
          "invalid map file: seen-free block " + std::to_string(n) + " is out of order or padded";
      return false;
    }
    out->blocks.emplace_back(key, bits);
    *r += kMapFileFreeSpaceRecordBytes;
  }
  return true;
}
}  // namespace

bool decodeMapFile(const uint8_t* data, size_t size, const MapperConfig& config, BlockOctree* out,
                   MapFileInfo* info, std::string* error) {
  size_t header_bytes = 0;
  if (!decodeMapHeader(data, size, size, info, &header_bytes, error)) return false;
  info->last_update_frames.clear();
  info->free_space = SeenFreeSpace();
  const bool v1 = info->version == 1;
  const size_t payload_crc_at = v1 ? 64 : 72;
  const size_t payload_bytes = size - header_bytes;
  const uint8_t* payload = data + header_bytes;
  if (getU32(data + payload_crc_at) != crc32(payload, payload_bytes)) {
    *error = "corrupted map file: block data checksum mismatch";
    return false;
  }
  if (info->voxel_size_m != config.voxel_size_m || info->truncation_vox != config.truncation_vox) {
    *error = "map file was built with voxel_size_m = " + number(info->voxel_size_m) +
             ", truncation_vox = " + number(info->truncation_vox) +
             " but this mapper uses voxel_size_m = " + number(config.voxel_size_m) +
             ", truncation_vox = " + number(config.truncation_vox);
    return false;
  }
  if (out->blockCount() != 0 || out->blockSize() != config.blockSizeM()) {
    *error = "map file must be decoded into an empty octree of the configured block size";
    return false;
  }
  const uint8_t* r = payload;
  const uint8_t* const payload_end = payload + payload_bytes;
  for (uint64_t n = 0; n < info->block_count; ++n) {
    if (static_cast<size_t>(payload_end - r) < kMapFileRecordHeadBytes) {
      *error = "invalid map file: block " + std::to_string(n) + " of " +
               std::to_string(info->block_count) + " runs past the end of the file";
      return false;
    }
    const BlockKey key{static_cast<int32_t>(getU32(r)), static_cast<int32_t>(getU32(r + 4)),
                       static_cast<int32_t>(getU32(r + 8))};
    auto which = [&] {  // only built for an error message
      return "block " + std::to_string(n) + " (key " + std::to_string(key.x) + ", " +
             std::to_string(key.y) + ", " + std::to_string(key.z) + ")";
    };
    // Version 1: derived mesh level and sign flags at 20, 21 (checked, then recomputed);
    // version 2: the stored levels at 20, then zeros.
    const uint8_t mask = v1 ? 0b111 : r[20];
    const bool valid = v1 ? static_cast<int8_t>(r[20]) >= 0 &&
                                static_cast<int8_t>(r[20]) < kNumLevels && r[21] <= 3
                          : mask <= 0b111 && r[21] == 0 && r[22] == 0 && r[23] == 0;
    if (!valid) {
      *error = "invalid map file: " + which() + " has head bytes " + std::to_string(r[20]) + ", " +
               std::to_string(r[21]) + ", " + std::to_string(r[22]) + ", " + std::to_string(r[23]) +
               (v1 ? " (mesh level, flags, 0, 0)" : " (levels, 0, 0, 0)");
      return false;
    }
    const size_t record_bytes = kMapFileRecordHeadBytes + levelBytes(mask);
    if (static_cast<size_t>(payload_end - r) < record_bytes) {
      *error = "invalid map file: " + which() + " runs past the end of the file";
      return false;
    }
    // The stored levels, checked; a level is kept only if it holds an observed voxel, as
    // fusion allocates them. Version 1 stored all three levels of every block the lookup had
    // reached: its unobserved levels, and blocks with none observed, are dropped (they read the
    // same as no storage). Version 2 stores only such levels: anything else is invalid.
    std::array<std::vector<Voxel>, kNumLevels> kept;
    const uint8_t* in = r + kMapFileRecordHeadBytes;
    bool any_kept = false;
    for (int l = 0; l < kNumLevels; ++l) {
      if (!(mask & (1u << l))) continue;
      std::vector<Voxel> voxels(levelVoxelCount(l));
      loadVoxels(in, levelVoxelCount(l), voxels.data());
      in += levelVoxelCount(l) * kVoxelRecordBytes;
      bool observed = false;
      for (const Voxel& voxel : voxels) {
        if (!std::isfinite(voxel.sdf_m) || !std::isfinite(voxel.weight) || voxel.weight < 0.0f) {
          *error =
              "invalid map file: " + which() + " holds a non-finite distance or a negative weight";
          return false;
        }
        observed = observed || voxel.weight > 0.0f;
      }
      if (!observed && !v1) {
        *error = "invalid map file: " + which() + " stores level " + std::to_string(l) +
                 " without an observed voxel";
        return false;
      }
      if (observed) {
        kept[l] = std::move(voxels);
        any_kept = true;
      }
    }
    if (!any_kept && !v1) {
      *error = "invalid map file: " + which() + " stores no level";
      return false;
    }
    r += record_bytes;
    if (!any_kept) continue;  // a version-1 block nothing was fused into
    bool allocated = false;
    VoxelBlock* block = out->findOrAllocate(key, &allocated);
    if (block == nullptr || !allocated) {
      *error = "invalid map file: " + which() +
               (block ? " appears twice" : " is beyond the map's range");
      return false;
    }
    info->last_update_frames.emplace_back(key, getU64(r - record_bytes + 12));
    for (int l = 0; l < kNumLevels; ++l)
      if (!kept[l].empty()) block->adoptLevel(l, kept[l].data());
  }
  if (info->version >= 3 && !decodeFreeSpace(&r, payload_end, &info->free_space, error))
    return false;
  if (r != payload_end) {
    *error = "invalid map file: " + std::to_string(payload_end - r) + " bytes after the last of " +
             std::to_string(info->block_count) + " blocks";
    return false;
  }
  return true;
}

bool readMapFile(const std::string& path, const MapperConfig& config, BlockOctree* out,
                 MapFileInfo* info, std::string* error) {
  // Only regular files: a device such as /dev/zero would be read without end.
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) {
    *error = path + ": cannot open the map file (" + std::strerror(errno) + ")";
    return false;
  }
  if (!S_ISREG(st.st_mode)) {
    *error = path + ": not a regular file, so not a map file";
    return false;
  }
  std::ifstream f(path, std::ios::binary);
  if (!f) {
    // The stream keeps no cause; the OS's is in errno after the open it tried.
    *error = path + ": cannot open the map file (" + std::strerror(errno) + ")";
    return false;
  }
  // The header first: a file whose header is wrong, or announces another size than the file
  // has, is refused before its payload is read into memory (a 64 GiB sparse file costs nothing).
  const size_t file_size = static_cast<size_t>(st.st_size);
  const size_t head = std::min(file_size, kMapFileHeaderBytes);
  std::vector<uint8_t> bytes(head);
  auto read = [&](uint8_t* to, size_t n) {
    f.read(reinterpret_cast<char*>(to), static_cast<std::streamsize>(n));
    if (f.gcount() == static_cast<std::streamsize>(n)) return true;
    *error = path + ": read error (the file changed while it was read?)";
    return false;
  };
  if (!read(bytes.data(), head)) return false;
  size_t header_bytes = 0;
  MapFileInfo header_info;
  if (!decodeMapHeader(bytes.data(), head, file_size, &header_info, &header_bytes, error)) {
    *error = path + ": " + *error;
    return false;
  }
  try {
    bytes.resize(file_size);
  } catch (const std::bad_alloc&) {
    *error = path + ": not enough memory to read its " + std::to_string(file_size) + " bytes";
    return false;
  }
  if (!read(bytes.data() + head, file_size - head)) return false;
  if (!decodeMapFile(bytes.data(), bytes.size(), config, out, info, error)) {
    *error = path + ": " + *error;
    return false;
  }
  return true;
}

}  // namespace stereo_fusion
