#include "stereo_fusion/planning/EsdfPropagator.h"

#include <algorithm>
#include <queue>
#include <tuple>

namespace stereo_fusion {

namespace {

struct Ref {
  PlanningBlock* block = nullptr;
  int cell = 0;
};

bool lexLess(const CellIndex& a, const CellIndex& b) { return std::tie(a.z, a.y, a.x) < std::tie(b.z, b.y, b.x); }

uint32_t squaredDistance(const CellIndex& a, const CellIndex& b) {
  const int64_t dx = a.x - b.x, dy = a.y - b.y, dz = a.z - b.z;
  const int64_t d2 = dx * dx + dy * dy + dz * dz;
  return d2 > 0xFFFFFF ? 0xFFFFFFu : static_cast<uint32_t>(d2);
}

struct Entry {
  uint32_t dist2;
  CellIndex cell;
  bool operator>(const Entry& o) const { return dist2 > o.dist2; }
};

/// The propagation over one PlanningBlockMap: cell access with a one-block cache.
class Propagation {
 public:
  Propagation(PlanningBlockMap* blocks, uint32_t max_dist2) : blocks_(blocks), max_dist2_(max_dist2) {}

  Ref at(const CellIndex& c) {
    const BlockKey key = planningBlockOf(c);
    if (!(key == cached_key_) || !cached_valid_) {
      const auto it = blocks_->find(key);
      cached_block_ = it == blocks_->end() ? nullptr : it->second.get();
      cached_key_ = key;
      cached_valid_ = true;
    }
    return {cached_block_, cellInBlock(c)};
  }
  static bool occupied(const Ref& r) { return r.block && PlanningBlock::test(r.block->occupied, r.cell); }
  static CellIndex siteOf(const CellIndex& c, const Ref& r) {
    const auto& s = r.block->site[r.cell];
    return c.offset(s[0], s[1], s[2]);
  }
  bool siteValid(const CellIndex& c, const Ref& r) {
    if (r.block->dist2[r.cell] == PlanningBlock::kNoSite) return false;
    const bool own = occupied(r);
    return occupied(at(siteOf(c, r))) != own;
  }
  void clearSite(const Ref& r) { r.block->dist2[r.cell] = PlanningBlock::kNoSite; }

  /// Gives `n` the site `candidate` if it is nearer (or as near and smaller) than its own.
  void consider(const CellIndex& n, const Ref& rn, const CellIndex& candidate) {
    const uint32_t d2 = squaredDistance(candidate, n);
    if (d2 > max_dist2_) return;
    const uint16_t current = rn.block->dist2[rn.cell];
    if (current != PlanningBlock::kNoSite &&
        !(d2 < current || (d2 == current && lexLess(candidate, siteOf(n, rn)))))
      return;
    rn.block->dist2[rn.cell] = static_cast<uint16_t>(d2);
    rn.block->site[rn.cell] = {static_cast<int8_t>(candidate.x - n.x), static_cast<int8_t>(candidate.y - n.y),
                               static_cast<int8_t>(candidate.z - n.z)};
    open_.push({d2, n});
    ++lowered_;
  }

  /// `c` offers itself (to neighbours of the other kind) or its site (to those of its kind).
  void offerToNeighbours(const CellIndex& c) {
    const Ref rc = at(c);
    if (!rc.block) return;
    const bool own = occupied(rc);
    const bool has_site = siteValid(c, rc);
    const CellIndex site = has_site ? siteOf(c, rc) : c;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          if (!(dx | dy | dz)) continue;
          const CellIndex n = c.offset(dx, dy, dz);
          const Ref rn = at(n);
          if (!rn.block) continue;
          if (occupied(rn) != own)
            consider(n, rn, c);
          else if (has_site)
            consider(n, rn, site);
        }
  }

  /// The best site `c` can read off its neighbours directly (after its own was cleared).
  void reseed(const CellIndex& c) {
    const Ref rc = at(c);
    if (!rc.block) return;
    const bool own = occupied(rc);
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          if (!(dx | dy | dz)) continue;
          const CellIndex n = c.offset(dx, dy, dz);
          const Ref rn = at(n);
          if (!rn.block) {
            if (own) consider(c, at(c), n);  // outside every block: not occupied
            continue;
          }
          if (occupied(rn) != own) {
            consider(c, at(c), n);
          } else if (siteValid(n, rn)) {
            const CellIndex s = siteOf(n, rn);
            consider(c, at(c), s);
          }
        }
  }

  void lower() {
    while (!open_.empty()) {
      const Entry e = open_.top();
      open_.pop();
      const Ref r = at(e.cell);
      if (!r.block || r.block->dist2[r.cell] != e.dist2) continue;  // superseded
      offerToNeighbours(e.cell);
    }
  }

  /// Clears every cell whose site stopped being of the other kind, outwards from `seeds`
  /// (already cleared); returns the cleared cells, seeds included.
  std::vector<CellIndex> raise(const std::vector<CellIndex>& seeds) {
    std::vector<CellIndex> cleared = seeds;
    for (size_t i = 0; i < cleared.size(); ++i) {
      const CellIndex c = cleared[i];
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            if (!(dx | dy | dz)) continue;
            const CellIndex n = c.offset(dx, dy, dz);
            const Ref rn = at(n);
            if (!rn.block || rn.block->dist2[rn.cell] == PlanningBlock::kNoSite) continue;
            if (siteValid(n, rn)) continue;
            clearSite(at(n));
            cleared.push_back(n);
          }
    }
    return cleared;
  }

  void invalidateCache() { cached_valid_ = false; }
  uint64_t lowered() const { return lowered_; }

 private:
  PlanningBlockMap* blocks_;
  uint32_t max_dist2_;
  BlockKey cached_key_;
  bool cached_valid_ = false;
  PlanningBlock* cached_block_ = nullptr;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open_;
  uint64_t lowered_ = 0;
};

}  // namespace

bool cellOccupied(const PlanningBlockMap& blocks, const CellIndex& cell) {
  const auto it = blocks.find(planningBlockOf(cell));
  return it != blocks.end() && PlanningBlock::test(it->second->occupied, cellInBlock(cell));
}

EsdfStats EsdfPropagator::update(PlanningBlockMap* blocks, const std::vector<CellIndex>& flipped,
                                 const std::vector<BlockKey>& fresh, uint32_t max_dist2) {
  EsdfStats stats;
  stats.cells_flipped = flipped.size();
  Propagation p(blocks, max_dist2);
  std::vector<CellIndex> seeds;
  for (const CellIndex& c : flipped) {
    const Ref r = p.at(c);
    if (!r.block) continue;
    p.clearSite(r);
    seeds.push_back(c);
  }
  const std::vector<CellIndex> cleared = p.raise(seeds);
  stats.cells_raised = cleared.size();
  for (const CellIndex& c : cleared) p.reseed(c);
  for (const BlockKey& key : fresh)
    for (int cell = 0; cell < PlanningBlock::kCells; ++cell) p.reseed(cellOf(key, cell));
  // A flipped cell is a new site for its neighbours of the other kind, whatever its own site.
  for (const CellIndex& c : flipped) p.offerToNeighbours(c);
  p.lower();
  stats.cells_lowered = p.lowered();
  return stats;
}

EsdfStats EsdfPropagator::rebuild(PlanningBlockMap* blocks, uint32_t max_dist2) {
  EsdfStats stats;
  std::vector<CellIndex> occupied;
  for (auto& [key, block] : *blocks) {
    block->dist2.fill(PlanningBlock::kNoSite);
    for (int cell = 0; cell < PlanningBlock::kCells; ++cell)
      if (PlanningBlock::test(block->occupied, cell)) occupied.push_back(cellOf(key, cell));
  }
  // Sorted: the same map gives the same queue order, whatever the hash table's.
  std::sort(occupied.begin(), occupied.end(), lexLess);
  Propagation p(blocks, max_dist2);
  for (const CellIndex& c : occupied) p.reseed(c);
  for (const CellIndex& c : occupied) p.offerToNeighbours(c);
  p.lower();
  stats.cells_lowered = p.lowered();
  return stats;
}

}  // namespace stereo_fusion
