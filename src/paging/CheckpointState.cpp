#include "stereo_fusion/paging/CheckpointState.h"

#include "stereo_fusion/io/ByteCodec.h"

namespace stereo_fusion {

namespace {
void putKey(const BlockKey& key, ByteWriter* out) {
  out->put<int32_t>(key.x);
  out->put<int32_t>(key.y);
  out->put<int32_t>(key.z);
}

BlockKey getKey(ByteReader* in) {
  BlockKey key;
  key.x = in->get<int32_t>();
  key.y = in->get<int32_t>();
  key.z = in->get<int32_t>();
  return key;
}

constexpr size_t kKeyBytes = 12;

void putText(const std::string& text, ByteWriter* out) {
  out->put<uint64_t>(text.size());
  out->putBytes(text.data(), text.size());
}

bool getText(ByteReader* in, std::string* text) {
  const uint64_t bytes = in->get<uint64_t>();
  if (!in->ok() || bytes > in->remaining()) return false;
  text->assign(reinterpret_cast<const char*>(in->position()), bytes);
  in->skip(bytes);
  return true;
}
}  // namespace

std::vector<uint8_t> encodeCheckpointState(const CheckpointState& state) {
  std::vector<uint8_t> bytes;
  ByteWriter out(&bytes);
  out.put<uint32_t>(kCheckpointMagic);
  out.put<uint32_t>(kCheckpointVersion);
  out.put<uint64_t>(state.frames_integrated);
  out.put<double>(state.free_space.cell_m);
  out.put<uint64_t>(state.free_space.blocks.size());
  for (const auto& [key, bits] : state.free_space.blocks) {
    putKey(key, &out);
    for (const uint64_t word : bits) out.put<uint64_t>(word);
  }
  out.put<uint64_t>(state.pending.size());
  for (const CheckpointState::Pending& pending : state.pending) {
    putText(pending.consumer, &out);
    for (const std::vector<BlockKey>* keys : {&pending.updated, &pending.erased}) {
      out.put<uint64_t>(keys->size());
      for (const BlockKey& key : *keys) putKey(key, &out);
    }
  }
  putText(state.owner_note, &out);
  return bytes;
}

bool decodeCheckpointState(const std::vector<uint8_t>& bytes, CheckpointState* state,
                           std::string* error) {
  ByteReader in(bytes.data(), bytes.size());
  *state = CheckpointState();
  if (in.get<uint32_t>() != kCheckpointMagic || in.get<uint32_t>() != kCheckpointVersion ||
      !in.ok()) {
    *error = "its checkpoint record is not one (magic or version)";
    return false;
  }
  state->frames_integrated = in.get<uint64_t>();
  state->free_space.cell_m = in.get<double>();
  const uint64_t free_blocks = in.get<uint64_t>();
  constexpr size_t kFreeRecordBytes = kKeyBytes + sizeof(PlanningBlock::Bits);
  if (!in.ok() || free_blocks > in.remaining() / kFreeRecordBytes) {
    *error = "its checkpoint record is cut short (free space)";
    return false;
  }
  state->free_space.blocks.resize(free_blocks);
  for (auto& [key, bits] : state->free_space.blocks) {
    key = getKey(&in);
    for (uint64_t& word : bits) word = in.get<uint64_t>();
  }
  const uint64_t consumers = in.get<uint64_t>();
  if (!in.ok() || consumers > in.remaining() / (3 * sizeof(uint64_t))) {
    *error = "its checkpoint record is cut short (pending changes)";
    return false;
  }
  state->pending.resize(consumers);
  for (CheckpointState::Pending& pending : state->pending) {
    if (!getText(&in, &pending.consumer)) {
      *error = "its checkpoint record is cut short (pending changes)";
      return false;
    }
    for (std::vector<BlockKey>* keys : {&pending.updated, &pending.erased}) {
      const uint64_t count = in.get<uint64_t>();
      if (!in.ok() || count > in.remaining() / kKeyBytes) {
        *error = "its checkpoint record is cut short (pending changes)";
        return false;
      }
      keys->resize(count);
      for (BlockKey& key : *keys) key = getKey(&in);
    }
  }
  if (!getText(&in, &state->owner_note) || in.remaining() != 0) {
    *error = "its checkpoint record is cut short or too long (owner's note)";
    return false;
  }
  return true;
}

}  // namespace stereo_fusion
