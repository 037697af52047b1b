// The checkpoint record: what it holds comes back, and a record cut at any length, or with
// another magic, is refused with a sentence.
#include <gtest/gtest.h>

#include "stereo_fusion/paging/CheckpointState.h"

using namespace stereo_fusion;

TEST(CheckpointState, RoundTripsAndRefusesEveryCutOrForeignRecord) {
  CheckpointState state;
  state.frames_integrated = 1234567890123ull;
  state.free_space.cell_m = 0.08;
  PlanningBlock::Bits bits{};
  bits[0] = 0x8000000000000001ull;
  bits[7] = 42;
  state.free_space.blocks = {{{-1, 2, -3}, bits}, {{4, 5, 6}, PlanningBlock::Bits{}}};
  state.pending = {{"mesher", {{0, 0, 0}, {1, -1, 2}}, {{3, 3, 3}}}, {"eviction", {}, {}}};
  state.owner_note = "input=/data/seq\nnext_frame=17";
  const std::vector<uint8_t> bytes = encodeCheckpointState(state);
  // 8 head + 8 frames + 8 cell + 8 count + 2 × (12 + 64) + 8 count + (8 + 6 + 8 + 2 × 12 + 8 +
  // 12) + (8 + 8 + 8 + 8) + 8 + note.
  EXPECT_EQ(bytes.size(), 8u + 8 + 8 + 8 + 2 * 76 + 8 + (8 + 6 + 8 + 24 + 8 + 12) + 32 + 8 +
                              state.owner_note.size());
  CheckpointState back;
  std::string error;
  ASSERT_TRUE(decodeCheckpointState(bytes, &back, &error)) << error;
  EXPECT_EQ(back.frames_integrated, state.frames_integrated);
  EXPECT_EQ(back.free_space.cell_m, 0.08);
  ASSERT_EQ(back.free_space.blocks.size(), 2u);
  EXPECT_EQ(back.free_space.blocks[0].first, (BlockKey{-1, 2, -3}));
  EXPECT_EQ(back.free_space.blocks[0].second, bits);
  ASSERT_EQ(back.pending.size(), 2u);
  EXPECT_EQ(back.pending[0].consumer, "mesher");
  EXPECT_EQ(back.pending[0].updated, state.pending[0].updated);
  EXPECT_EQ(back.pending[0].erased, state.pending[0].erased);
  EXPECT_EQ(back.pending[1].consumer, "eviction");
  EXPECT_EQ(back.owner_note, state.owner_note);
  for (size_t n = 0; n < bytes.size(); ++n) {
    const std::vector<uint8_t> cut(bytes.begin(), bytes.begin() + static_cast<long>(n));
    error.clear();
    EXPECT_FALSE(decodeCheckpointState(cut, &back, &error)) << "cut at " << n;
    EXPECT_FALSE(error.empty()) << "cut at " << n;
  }
  std::vector<uint8_t> longer = bytes;
  longer.push_back(0);
  EXPECT_FALSE(decodeCheckpointState(longer, &back, &error));
  std::vector<uint8_t> foreign = bytes;
  foreign[0] ^= 1;
  EXPECT_FALSE(decodeCheckpointState(foreign, &back, &error));
  EXPECT_NE(error.find("magic"), std::string::npos) << error;
}
