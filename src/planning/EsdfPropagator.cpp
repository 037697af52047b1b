#include "stereo_fusion/planning/EsdfPropagator.h"

#include <algorithm>
#include <array>
#include <tuple>

namespace stereo_fusion {

namespace {

struct Ref {
  PlanningBlock* block = nullptr;
  int cell = 0;
};

bool lexLess(const CellIndex& a, const CellIndex& b) {
  return std::tie(a.z, a.y, a.x) < std::tie(b.z, b.y, b.x);
}

uint32_t squaredDistance(const CellIndex& a, const CellIndex& b) {
  const int64_t dx = a.x - b.x, dy = a.y - b.y, dz = a.z - b.z;
  const int64_t d2 = dx * dx + dy * dy + dz * dz;
  return d2 > 0xFFFFFF ? 0xFFFFFFu : static_cast<uint32_t>(d2);
}

/// Cells waiting to offer their sites, by squared distance: a bucket per value (at most
/// max_dist2 + 1 of them), so a push and a pop cost O(1) instead of a heap's O(log n).
class BucketQueue {
 public:
  explicit BucketQueue(uint32_t max_dist2) : buckets_(max_dist2 + 1) {}
  void push(uint32_t dist2, const CellIndex& cell) {
    buckets_[dist2].push_back(cell);
    lowest_ = std::min(lowest_, dist2);
    ++size_;
  }
  bool empty() const { return size_ == 0; }
  /// The cell with the smallest key (any of them), and that key.
  CellIndex pop(uint32_t* dist2) {
    while (buckets_[lowest_].empty()) ++lowest_;
    const CellIndex cell = buckets_[lowest_].back();
    buckets_[lowest_].pop_back();
    --size_;
    *dist2 = lowest_;
    return cell;
  }

 private:
  std::vector<std::vector<CellIndex>> buckets_;
  uint32_t lowest_ = 0;
  size_t size_ = 0;
};

/// Calls fn(n) for the 26 neighbours n of `c` (faces, edges, corners). `c` by value: `fn` may
/// grow the container it came from.
template <typename Fn>
void forEachNeighbour(const CellIndex c, Fn&& fn) {
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx)
        if (dx | dy | dz) fn(c.offset(dx, dy, dz));
}

/// The propagation over one PlanningBlockMap: cell access through a small block cache.
class Propagation {
 public:
  Propagation(PlanningBlockMap* blocks, uint32_t max_dist2)
      : blocks_(blocks), max_dist2_(max_dist2), open_(max_dist2) {}

  Ref at(const CellIndex& c) {
    const BlockKey key = planningBlockOf(c);
    // A direct-mapped cache of blocks (present or absent): a cell's 26 neighbours and their
    // sites lie in a handful of blocks, and the table is not changed while this runs.
    CacheEntry& entry =
        cache_[(static_cast<uint32_t>(key.x) * 7u + static_cast<uint32_t>(key.y) * 13u +
                static_cast<uint32_t>(key.z) * 31u) &
               (kCacheSize - 1)];
    if (!entry.valid || !(entry.key == key)) {
      const auto it = blocks_->find(key);
      entry.block = it == blocks_->end() ? nullptr : it->second.get();
      entry.key = key;
      entry.valid = true;
    }
    return {entry.block, cellInBlock(c)};
  }
  static bool occupied(const Ref& r) {
    return r.block && PlanningBlock::test(r.block->occupied, r.cell);
  }
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

  /// Gives `n` the site `candidate` if it is nearer than its own, or as near and smaller in
  /// coordinates: the site among equally near ones does not depend on the order of the offers,
  /// so an incremental update picks the one a rebuild picks (distances read the site's
  /// centre_sdf: equally near sites give different sub-cell distances).
  void consider(const CellIndex& n, const Ref& rn, const CellIndex& candidate) {
    const uint32_t d2 = squaredDistance(candidate, n);
    if (d2 > max_dist2_) return;
    const uint16_t current = rn.block->dist2[rn.cell];
    if (current != PlanningBlock::kNoSite &&
        (d2 > current || (d2 == current && !lexLess(candidate, siteOf(n, rn)))))
      return;
    rn.block->dist2[rn.cell] = static_cast<uint16_t>(d2);
    rn.block->site[rn.cell] = {static_cast<int8_t>(candidate.x - n.x),
                               static_cast<int8_t>(candidate.y - n.y),
                               static_cast<int8_t>(candidate.z - n.z)};
    open_.push(d2, n);
    ++lowered_;
  }

  /// `c` offers itself (to neighbours of the other kind) or its site (to those of its kind).
  void offerToNeighbours(const CellIndex& c) {
    const Ref rc = at(c);
    if (!rc.block) return;
    const bool own = occupied(rc);
    const bool has_site = siteValid(c, rc);
    const CellIndex site = has_site ? siteOf(c, rc) : c;
    const int s = PlanningBlock::kSide;
    const int li = rc.cell % s, lj = (rc.cell / s) % s, lk = rc.cell / (s * s);
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          if (!(dx | dy | dz)) continue;
          const CellIndex n = c.offset(dx, dy, dz);
          // Most neighbours share c's block: no lookup for them.
          const int i = li + dx, j = lj + dy, k = lk + dz;
          const Ref rn = (i >= 0 && i < s && j >= 0 && j < s && k >= 0 && k < s)
                             ? Ref{rc.block, PlanningBlock::index(i, j, k)}
                             : at(n);
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
    forEachNeighbour(c, [&](const CellIndex& n) {
      const Ref rn = at(n);
      if (!rn.block) {
        if (own) consider(c, at(c), n);  // outside every block: not occupied
      } else if (occupied(rn) != own) {
        consider(c, at(c), n);
      } else if (siteValid(n, rn)) {
        const CellIndex s = siteOf(n, rn);
        consider(c, at(c), s);
      }
    });
  }

  void lower() {
    while (!open_.empty()) {
      uint32_t dist2;
      const CellIndex cell = open_.pop(&dist2);
      const Ref r = at(cell);
      if (!r.block || r.block->dist2[r.cell] != dist2) continue;  // superseded
      offerToNeighbours(cell);
    }
  }

  /// Clears every cell whose site stopped being of the other kind, outwards from `seeds`
  /// (already cleared); returns the cleared cells, seeds included.
  std::vector<CellIndex> raise(const std::vector<CellIndex>& seeds) {
    std::vector<CellIndex> cleared = seeds;
    for (size_t i = 0; i < cleared.size(); ++i) {
      forEachNeighbour(cleared[i], [&](const CellIndex& n) {
        const Ref rn = at(n);
        if (!rn.block || rn.block->dist2[rn.cell] == PlanningBlock::kNoSite || siteValid(n, rn))
          return;
        clearSite(at(n));
        cleared.push_back(n);
      });
    }
    return cleared;
  }

  uint64_t lowered() const { return lowered_; }

 private:
  struct CacheEntry {
    BlockKey key;
    PlanningBlock* block = nullptr;
    bool valid = false;
  };
  static constexpr uint32_t kCacheSize = 64;
  PlanningBlockMap* blocks_;
  uint32_t max_dist2_;
  std::array<CacheEntry, kCacheSize> cache_{};
  BucketQueue open_;
  uint64_t lowered_ = 0;
};

/// Gives the cells of freshly allocated blocks (no site yet) what their neighbours offer.
/// Only a cell next to an older block can read a site there, and only an occupied one can read
/// the space outside every block (its inside distance); the others start with nothing to read:
/// the lower wavefront reaches them from those, and from the flipped cells' offers.
void reseedFresh(Propagation* p, const PlanningBlockMap& blocks, std::vector<BlockKey> fresh) {
  std::sort(fresh.begin(), fresh.end());
  const int last = PlanningBlock::kSide - 1;
  for (const BlockKey& key : fresh) {
    const PlanningBlock& block = *blocks.at(key);
    bool older[3][3][3];  // neighbour block (dx + 1, dy + 1, dz + 1) exists and is not fresh
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const BlockKey n = key.offset(dx, dy, dz);
          older[dz + 1][dy + 1][dx + 1] = (dx | dy | dz) && blocks.count(n) &&
                                          !std::binary_search(fresh.begin(), fresh.end(), n);
        }
    for (int k = 0; k <= last; ++k)
      for (int j = 0; j <= last; ++j)
        for (int i = 0; i <= last; ++i) {
          const int cell = PlanningBlock::index(i, j, k);
          bool reads = PlanningBlock::test(block.occupied, cell);
          // The neighbour blocks this cell touches: offsets 0 and, on a face, ±1.
          for (int dz = (k == 0 ? -1 : 0); !reads && dz <= (k == last ? 1 : 0); ++dz)
            for (int dy = (j == 0 ? -1 : 0); !reads && dy <= (j == last ? 1 : 0); ++dy)
              for (int dx = (i == 0 ? -1 : 0); !reads && dx <= (i == last ? 1 : 0); ++dx)
                reads = older[dz + 1][dy + 1][dx + 1];
          if (reads) p->reseed(cellOf(key, cell));
        }
  }
}

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
  reseedFresh(&p, *blocks, fresh);
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
