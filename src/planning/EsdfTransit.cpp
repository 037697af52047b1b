#include "stereo_fusion/planning/EsdfTransit.h"

#include <algorithm>
#include <utility>

namespace stereo_fusion {

namespace {

constexpr int kSide = PlanningBlock::kSide;

/// The box around the set bits' cells; words are z layers of 8 rows (y) of 8 bits (x).
CellBox boxOfBits(const BlockKey& key, const PlanningBlock::Bits& bits) {
  CellBox box;
  box.min = Eigen::Vector3i::Constant(kSide);
  box.max = Eigen::Vector3i::Zero();
  uint64_t rows = 0;  // a bit per x, over every row and layer
  uint32_t ys = 0;    // a bit per y
  for (int z = 0; z < kSide; ++z) {
    const uint64_t layer = bits[z];
    if (!layer) continue;
    box.min.z() = std::min(box.min.z(), z);
    box.max.z() = z + 1;
    for (int y = 0; y < kSide; ++y) {
      const uint64_t row = (layer >> (kSide * y)) & 0xFFu;
      if (!row) continue;
      ys |= 1u << y;
      rows |= row;
    }
  }
  if (box.max.z() == 0) return CellBox{};
  box.min.x() = __builtin_ctzll(rows);
  box.max.x() = 64 - __builtin_clzll(rows);
  box.min.y() = __builtin_ctz(ys);
  box.max.y() = 32 - __builtin_clz(ys);
  const Eigen::Vector3i origin(key.x * kSide, key.y * kSide, key.z * kSide);
  box.min += origin;
  box.max += origin;
  return box;
}

}  // namespace

static_assert(PlanningBlock::kCells == 64 * kSide, "a Bits word is one z layer");

uint8_t blockKinds(const PlanningBlock& block) {
  uint8_t kinds = 0;
  for (size_t w = 0; w < block.occupied.size(); ++w) {
    if (block.occupied[w]) kinds |= kHoldsOccupied;
    if ((block.seen_free[w] | block.tsdf_observed[w]) & ~block.occupied[w]) kinds |= kHoldsFree;
  }
  return kinds;
}

CellBox occupiedBox(const BlockKey& key, const PlanningBlock& block) {
  return boxOfBits(key, block.occupied);
}

CellBox freeBox(const BlockKey& key, const PlanningBlock& block) {
  PlanningBlock::Bits free;
  for (size_t w = 0; w < free.size(); ++w)
    free[w] = (block.seen_free[w] | block.tsdf_observed[w]) & ~block.occupied[w];
  return boxOfBits(key, free);
}

CellBox blockBox(const BlockKey& key) {
  CellBox box;
  box.min = Eigen::Vector3i(key.x, key.y, key.z) * kSide;
  box.max = box.min + Eigen::Vector3i::Constant(kSide);
  return box;
}

EsdfTransit::EsdfTransit(uint32_t max_dist2) : max_dist2_(max_dist2) {
  // The largest block offset r whose nearest cells, s·r − (s − 1) apart, are within reach.
  const int64_t s = kSide;
  reach_ = 0;
  while ((s * (reach_ + 1) - (s - 1)) * (s * (reach_ + 1) - (s - 1)) <= int64_t{max_dist2})
    ++reach_;
  // The offsets whose blocks hold cells within reach of the origin block's (the corners of the
  // cube of the reach do not).
  const CellBox origin = blockBox({0, 0, 0});
  for (int dz = -reach_; dz <= reach_; ++dz)
    for (int dy = -reach_; dy <= reach_; ++dy)
      for (int dx = -reach_; dx <= reach_; ++dx)
        if ((dx | dy | dz) && withinReach(origin, blockBox({dx, dy, dz})))
          offsets_.emplace_back(dx, dy, dz);
}

bool EsdfTransit::withinReach(const CellBox& a, const CellBox& b) const {
  int64_t gap2 = 0;
  for (int i = 0; i < 3; ++i) {
    // Between the nearest cell centres of the two boxes along this axis.
    const int64_t gap = std::max<int64_t>({0, b.min[i] - a.max[i] + 1, a.min[i] - b.max[i] + 1});
    gap2 += gap * gap;
  }
  return gap2 <= int64_t{max_dist2_};
}

bool EsdfTransit::overlapsHull(const CellBox& c, const CellBox& p, const CellBox& q) {
  // The hull is the union over t ∈ [0, 1] of the boxes (1 − t)·p + t·q; c overlaps one of them
  // when, on every axis, its lower end lies below c's upper end and its upper end above c's
  // lower end: linear constraints on t, solved as an interval.
  constexpr double kMargin = 1e-6;  // in cells: touching is not overlapping
  double lo = 0.0, hi = 1.0;
  auto below = [&](double a, double b, double limit) {  // a + b·t ≤ limit
    if (b == 0.0) {
      if (a > limit) hi = -1.0;
    } else if (b > 0.0) {
      hi = std::min(hi, (limit - a) / b);
    } else {
      lo = std::max(lo, (limit - a) / b);
    }
  };
  for (int i = 0; i < 3; ++i) {
    below(p.min[i], q.min[i] - p.min[i], c.max[i] - kMargin);
    below(-p.max[i], -(q.max[i] - p.max[i]), -c.min[i] - kMargin);
  }
  return lo <= hi;
}

const PlanningBlock& EsdfTransit::summarized(const BlockKey& key,
                                             const PlanningBlock& block) const {
  if (block.summary_pass != pass_) {
    block.summary_pass = pass_;
    block.summary_kinds = blockKinds(block);
    block.summary_occupied = occupiedBox(key, block);
    block.summary_free = freeBox(key, block);
  }
  return block;
}

std::vector<BlockKey> EsdfTransit::needed(const PlanningBlockMap& blocks, const BlockKey& key,
                                          uint8_t kinds) const {
  const auto self = blocks.find(key);
  if (self == blocks.end()) return {};
  const PlanningBlock& own = summarized(key, *self->second);
  kinds &= own.summary_kinds;
  const CellBox& own_occupied = own.summary_occupied;
  const CellBox& own_free = own.summary_free;
  // Per offset in the cube of the reach: whether that block is absent, and whether needed.
  const int r = reach_, side = 2 * r + 1;
  enum : uint8_t { kPresent = 0, kAbsent = 1, kNeeded = 2 };
  std::vector<uint8_t> state(side * side * side, kPresent);
  auto at = [&](int dx, int dy, int dz) -> uint8_t& {
    return state[((dz + r) * side + (dy + r)) * side + (dx + r)];
  };
  std::vector<std::pair<CellBox, CellBox>> pairs;  // occupied box, free box within reach
  // A partner lies at an offset within reach; a block between the two at an offset no farther
  // on any axis, so within reach too: the offsets within reach are all there is to look at.
  for (const Eigen::Vector3i& d : offsets_) {
    const BlockKey other = key.offset(d.x(), d.y(), d.z());
    const auto it = blocks.find(other);
    if (it == blocks.end()) {
      at(d.x(), d.y(), d.z()) = kAbsent;
      continue;
    }
    const PlanningBlock& theirs = summarized(other, *it->second);
    if ((kinds & kHoldsOccupied) && (theirs.summary_kinds & kHoldsFree) &&
        withinReach(own_occupied, theirs.summary_free))
      pairs.emplace_back(own_occupied, theirs.summary_free);
    if ((kinds & kHoldsFree) && (theirs.summary_kinds & kHoldsOccupied) &&
        withinReach(theirs.summary_occupied, own_free))
      pairs.emplace_back(theirs.summary_occupied, own_free);
  }
  // Each pair's hull lies in the box around both: only the absent blocks there are tried.
  for (const auto& [p, q] : pairs) {
    const Eigen::Vector3i lo = p.min.cwiseMin(q.min), hi = p.max.cwiseMax(q.max);
    Eigen::Vector3i first, last;
    for (int a = 0; a < 3; ++a) {
      const int origin = (a == 0 ? key.x : a == 1 ? key.y : key.z);
      first[a] = std::max(-r, floorDiv(lo[a], kSide) - origin);
      last[a] = std::min(r, floorDiv(hi[a] - 1, kSide) - origin);
    }
    for (int dz = first.z(); dz <= last.z(); ++dz)
      for (int dy = first.y(); dy <= last.y(); ++dy)
        for (int dx = first.x(); dx <= last.x(); ++dx) {
          uint8_t& s = at(dx, dy, dz);
          if (s == kAbsent && overlapsHull(blockBox(key.offset(dx, dy, dz)), p, q)) s = kNeeded;
        }
  }
  std::vector<BlockKey> out;
  for (int dz = -r; dz <= r; ++dz)
    for (int dy = -r; dy <= r; ++dy)
      for (int dx = -r; dx <= r; ++dx)
        if (at(dx, dy, dz) == kNeeded) out.push_back(key.offset(dx, dy, dz));
  return out;
}

}  // namespace stereo_fusion
