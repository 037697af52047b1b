#include "stereo_fusion/map/BlockOctree.h"

#include <algorithm>
#include <cmath>
#include <unordered_set>

#include "stereo_fusion/util/ThreadPool.h"

namespace stereo_fusion {

struct BlockOctree::Node {
  // 64-bit: a root spanning ±kMaxKey has corners beyond the int32 range.
  std::array<int64_t, 3> origin{};  // minimum corner, in blocks
  int height = 0;  // covers 2^height blocks per axis; children of height-1 nodes are blocks
  std::array<std::atomic<void*>, 8> child{};

  int64_t halfSide() const { return int64_t{1} << (height - 1); }
  std::array<int64_t, 3> centre() const {
    const int64_t h = halfSide();
    return {origin[0] + h, origin[1] + h, origin[2] + h};
  }
  /// Eq. 2.7–2.10 in 64-bit coordinates (see BlockOctree::octantIndex).
  int octantOf(const BlockKey& key) const {
    const auto c = centre();
    return 4 * (key.x >= c[0]) + 2 * (key.y >= c[1]) + (key.z >= c[2]);
  }
};

BlockOctree::BlockOctree(double block_size_m) : block_size_m_(block_size_m) {}
BlockOctree::~BlockOctree() = default;

BlockKey BlockOctree::keyForPoint(const Eigen::Vector3d& p_world) const {
  return keyForBlockCoordinates(p_world / block_size_m_);
}

Eigen::Vector3d BlockOctree::blockOrigin(const BlockKey& key) const {
  return Eigen::Vector3d(key.x, key.y, key.z) * block_size_m_;
}

int BlockOctree::octantIndex(const BlockKey& key, const BlockKey& centre) {
  return 4 * (key.x >= centre.x) + 2 * (key.y >= centre.y) + (key.z >= centre.z);
}

bool BlockOctree::contains(const Node* node, const BlockKey& key) {
  const int64_t side = int64_t{1} << node->height;
  auto in = [side](int64_t o, int32_t v) { return v >= o && v < o + side; };
  return in(node->origin[0], key.x) && in(node->origin[1], key.y) && in(node->origin[2], key.z);
}

BlockOctree::Node* BlockOctree::newNode(const std::array<int64_t, 3>& origin, int height) {
  nodes_.push_back(std::make_unique<Node>());
  Node* n = nodes_.back().get();
  n->origin = origin;
  n->height = height;
  return n;
}

VoxelBlock* BlockOctree::find(const BlockKey& key) const {
  searches_.fetch_add(1, std::memory_order_relaxed);
  const Node* root = root_.load(std::memory_order_acquire);
  if (root == nullptr || !contains(root, key)) return nullptr;
  return findBelow(root, key);
}

VoxelBlock* BlockOctree::findBelow(const Node* node, const BlockKey& key) {
  while (true) {
    void* next = node->child[node->octantOf(key)].load(std::memory_order_acquire);
    if (next == nullptr) return nullptr;
    if (node->height == 1) return static_cast<VoxelBlock*>(next);
    node = static_cast<const Node*>(next);
  }
}

Eigen::AlignedBox3d BlockOctree::boxOf(const std::array<int64_t, 3>& origin, int64_t side) const {
  const Eigen::Vector3d lo(static_cast<double>(origin[0]), static_cast<double>(origin[1]),
                           static_cast<double>(origin[2]));
  return Eigen::AlignedBox3d(
      lo * block_size_m_,
      (lo + Eigen::Vector3d::Constant(static_cast<double>(side))) * block_size_m_);
}

void BlockOctree::collectBelow(const Node* start, const BoxTest& may_contain,
                               std::vector<VoxelBlock*>* out) const {
  std::vector<const Node*> stack{start};
  while (!stack.empty()) {
    const Node* node = stack.back();
    stack.pop_back();
    if (!may_contain(boxOf(node->origin, int64_t{1} << node->height))) continue;
    if (node->height > 1) {
      for (int octant = 7; octant >= 0; --octant)  // pushed in reverse: visited 0..7
        if (void* child = node->child[octant].load(std::memory_order_acquire))
          stack.push_back(static_cast<const Node*>(child));
      continue;
    }
    for (int octant = 0; octant < 8; ++octant) {
      auto* block = static_cast<VoxelBlock*>(node->child[octant].load(std::memory_order_acquire));
      if (block == nullptr) continue;
      const std::array<int64_t, 3> origin{block->key.x, block->key.y, block->key.z};
      if (may_contain(boxOf(origin, 1))) out->push_back(block);
    }
  }
}

void BlockOctree::collectBlocks(const BoxTest& may_contain, std::vector<VoxelBlock*>* out,
                                ThreadPool* pool) const {
  const Node* root = root_.load(std::memory_order_acquire);
  if (root == nullptr) return;
  if (pool == nullptr || pool->size() < 2) return collectBelow(root, may_contain, out);
  // Subtrees to share out: nodes replaced by their children in octant order, so that their
  // results concatenated in this order are the depth-first order of the serial walk.
  std::vector<const Node*> frontier{root}, next;
  const size_t wanted = 16 * static_cast<size_t>(pool->size());
  while (frontier.size() < wanted) {
    next.clear();
    bool expanded = false;
    for (const Node* node : frontier) {
      if (node->height == 1 || !may_contain(boxOf(node->origin, int64_t{1} << node->height))) {
        next.push_back(node);  // a leaf node, or one the walk below rejects at once
        continue;
      }
      expanded = true;
      for (int octant = 0; octant < 8; ++octant)
        if (void* child = node->child[octant].load(std::memory_order_acquire))
          next.push_back(static_cast<const Node*>(child));
    }
    frontier.swap(next);
    if (!expanded) break;
  }
  std::vector<std::vector<VoxelBlock*>> found(frontier.size());
  pool->parallelFor(frontier.size(), 1, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) collectBelow(frontier[i], may_contain, &found[i]);
  });
  for (const auto& blocks : found) out->insert(out->end(), blocks.begin(), blocks.end());
}

void BlockOctree::growToContain(const BlockKey& key) {
  Node* root = root_.load(std::memory_order_relaxed);
  if (root == nullptr) {
    // First block: a height-1 root covering the 2×2×2 blocks with the key at its lower corner
    // aligned to even coordinates, so the tree stays aligned to powers of two.
    auto align = [](int32_t v) { return int64_t{v} & ~int64_t{1}; };
    root = newNode({align(key.x), align(key.y), align(key.z)}, 1);
    root_.store(root, std::memory_order_release);
  }
  while (!contains(root, key)) {
    // Double the root: towards the key on the axes that miss it, towards the world origin on
    // the others, so the tree stays balanced around the map and the height stays ≤ 31.
    const int64_t side = int64_t{1} << root->height;
    std::array<int64_t, 3> origin = root->origin;
    const int32_t k[3] = {key.x, key.y, key.z};
    for (int a = 0; a < 3; ++a) {
      const bool below = k[a] < origin[a];
      const bool above = k[a] >= origin[a] + side;
      if (below || (!above && origin[a] + side / 2 > 0)) origin[a] -= side;
    }
    Node* grown = newNode(origin, root->height + 1);
    const BlockKey old_corner{static_cast<int32_t>(root->origin[0]),
                              static_cast<int32_t>(root->origin[1]),
                              static_cast<int32_t>(root->origin[2])};
    grown->child[grown->octantOf(old_corner)].store(root, std::memory_order_relaxed);
    root_.store(grown, std::memory_order_release);
    root = grown;
  }
}

VoxelBlock* BlockOctree::findOrAllocate(const BlockKey& key, bool* allocated) {
  if (allocated) *allocated = false;
  if (!keyInRange(key)) return nullptr;
  if (VoxelBlock* existing = find(key)) return existing;
  return allocate(key, std::make_unique<VoxelBlock>(), allocated);
}

VoxelBlock* BlockOctree::insert(std::unique_ptr<VoxelBlock> block) {
  if (!block || !keyInRange(block->key)) return nullptr;
  const BlockKey key = block->key;
  bool created = false;
  VoxelBlock* placed = allocate(key, std::move(block), &created);
  return created ? placed : nullptr;
}

void BlockOctree::findOrAllocateBatch(const BlockKey* keys, size_t n, VoxelBlock** blocks,
                                      uint8_t* allocated) {
  searchBatch(keys, n, blocks, allocated);
}

void BlockOctree::findBatch(const BlockKey* keys, size_t n, VoxelBlock** blocks) const {
  // Without `allocated` nothing is allocated: the search alone, which is const.
  const_cast<BlockOctree*>(this)->searchBatch(keys, n, blocks, nullptr);
}

void BlockOctree::searchBatch(const BlockKey* keys, size_t n, VoxelBlock** blocks,
                              uint8_t* allocated) {
  size_t searched = 0;  // as findOrAllocate(): keys out of range are no search
  // path[0] is a root (the current one, or one since grown over: it still holds the same
  // subtree), path[i + 1] a child of path[i]. Nodes are never freed while searches may run,
  // so the path of the previous key stays valid across allocations, ours or other threads'.
  constexpr int kMaxPath = 64;  // > any height: the root stays ≤ 31 levels high
  const Node* path[kMaxPath];
  int depth = 0;
  for (size_t i = 0; i < n; ++i) {
    const BlockKey& key = keys[i];
    blocks[i] = nullptr;
    if (allocated) allocated[i] = 0;
    if (!keyInRange(key)) continue;
    ++searched;
    while (depth > 0 && !contains(path[depth - 1], key)) --depth;
    if (depth == 0) {
      const Node* root = root_.load(std::memory_order_acquire);
      if (root != nullptr && contains(root, key)) path[depth++] = root;
    }
    // The same descent as findBelow(), recording the path.
    void* found = nullptr;
    for (const Node* node = depth > 0 ? path[depth - 1] : nullptr; node != nullptr;) {
      void* next = node->child[node->octantOf(key)].load(std::memory_order_acquire);
      if (next == nullptr || node->height == 1) {
        found = next;
        break;
      }
      node = static_cast<const Node*>(next);
      path[depth++] = node;
    }
    if (found != nullptr) {
      blocks[i] = static_cast<VoxelBlock*>(found);
      continue;
    }
    if (!allocated) continue;
    bool created = false;
    blocks[i] = allocate(key, std::make_unique<VoxelBlock>(), &created);
    allocated[i] = created;
  }
  searches_.fetch_add(searched, std::memory_order_relaxed);
}

VoxelBlock* BlockOctree::allocate(const BlockKey& key, std::unique_ptr<VoxelBlock> fresh,
                                  bool* allocated) {
  // `fresh` is built before the lock: only inserting it needs it.
  std::lock_guard<std::mutex> lock(alloc_mutex_);
  growToContain(key);
  Node* node = root_.load(std::memory_order_relaxed);
  while (true) {
    std::atomic<void*>& slot = node->child[node->octantOf(key)];
    void* next = slot.load(std::memory_order_relaxed);
    if (node->height == 1) {
      if (next != nullptr) return static_cast<VoxelBlock*>(next);  // another thread won
      block_storage_.push_back(std::move(fresh));
      VoxelBlock* block = block_storage_.back().get();
      block->key = key;
      if (free_rows_.empty()) {
        block->row = row_count_++;
      } else {
        block->row = free_rows_.back();
        free_rows_.pop_back();
      }
      link(block);
      blocks_.push_back(block);
      slot.store(block, std::memory_order_release);
      if (allocated) *allocated = true;
      return block;
    }
    if (next == nullptr) {
      const int64_t h = node->halfSide();
      const auto c = node->centre();
      const std::array<int64_t, 3> child_origin{key.x >= c[0] ? c[0] : c[0] - h,
                                                key.y >= c[1] ? c[1] : c[1] - h,
                                                key.z >= c[2] ? c[2] : c[2] - h};
      Node* child = newNode(child_origin, node->height - 1);
      slot.store(child, std::memory_order_release);
      next = child;
    }
    node = static_cast<Node*>(next);
  }
}

void BlockOctree::link(VoxelBlock* block) {
  // The 26 searches share their path down to the deepest node that holds the whole 3×3×3
  // neighbourhood: start them there instead of at the root. The block's own path exists down
  // to its height-1 node (only the leaf slot is still empty), and a height-1 node, two blocks
  // wide, never holds three.
  const BlockKey& key = block->key;
  const Node* top = root_.load(std::memory_order_relaxed);
  while (top->height > 1) {
    const auto* child =
        static_cast<const Node*>(top->child[top->octantOf(key)].load(std::memory_order_relaxed));
    if (!contains(child, key.offset(-1, -1, -1)) || !contains(child, key.offset(1, 1, 1))) break;
    top = child;
  }
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if (dx == 0 && dy == 0 && dz == 0) continue;
        const BlockKey neighbour_key = key.offset(dx, dy, dz);
        // Outside `top` only when `top` is the root: then the neighbour does not exist.
        if (!contains(top, neighbour_key)) continue;
        VoxelBlock* other = findBelow(top, neighbour_key);
        if (other == nullptr) continue;
        const int slot = NeighbourLinks::slot(dx, dy, dz);
        block->neighbours.blocks_[slot] = other;
        other->neighbours.blocks_[NeighbourLinks::opposite(slot)] = block;
      }
}

void BlockOctree::unlink(VoxelBlock* block) {
  for (int slot = 0; slot < NeighbourLinks::kCount; ++slot)
    if (VoxelBlock* other = block->neighbours.blocks_[slot]) {
      other->neighbours.blocks_[NeighbourLinks::opposite(slot)] = nullptr;
      block->neighbours.blocks_[slot] = nullptr;
    }
}

int BlockOctree::height() const {
  const Node* root = root_.load(std::memory_order_acquire);
  return root ? root->height : 0;
}

BlockOctree::MemoryUse BlockOctree::memoryUse(bool with_levels) const {
  MemoryUse use;
  use.block_bytes = block_storage_.size() * sizeof(VoxelBlock);
  if (with_levels)
    for (const VoxelBlock* b : blocks_)
      for (int level = 0; level < kNumLevels; ++level)
        if (b->hasLevel(level)) {
          use.level_bytes[level] += levelVoxelCount(level) * sizeof(Voxel);
          ++use.level_blocks[level];
        }
  use.node_bytes = nodes_.size() * sizeof(Node);
  use.bookkeeping_bytes = blocks_.capacity() * sizeof(VoxelBlock*) +
                          block_storage_.capacity() * sizeof(std::unique_ptr<VoxelBlock>) +
                          nodes_.capacity() * sizeof(std::unique_ptr<Node>);
  return use;
}

double BlockOctree::bytesPerBlock() const {
  return blocks_.empty() ? 0.0 : static_cast<double>(memoryBytes()) / blocks_.size();
}

std::vector<VoxelBlock*> BlockOctree::blocksSortedByKey() const {
  std::vector<VoxelBlock*> sorted = blocks_;
  std::sort(sorted.begin(), sorted.end(),
            [](const VoxelBlock* a, const VoxelBlock* b) { return a->key < b->key; });
  return sorted;
}

void BlockOctree::clear() {
  std::lock_guard<std::mutex> lock(alloc_mutex_);
  root_.store(nullptr, std::memory_order_release);
  blocks_.clear();
  block_storage_.clear();
  nodes_.clear();
  free_rows_.clear();
  row_count_ = 0;
}

size_t BlockOctree::erase(const std::vector<BlockKey>& keys) {
  std::lock_guard<std::mutex> lock(alloc_mutex_);
  std::unordered_set<const void*> doomed_blocks, doomed_nodes;
  std::vector<VoxelBlock*> to_unlink;
  for (const BlockKey& key : keys) {
    Node* root = root_.load(std::memory_order_relaxed);
    if (root == nullptr || !keyInRange(key) || !contains(root, key)) continue;
    // Walk down remembering the path, so that emptied nodes can be unlinked bottom-up.
    std::vector<std::pair<Node*, int>> path;  // node, octant taken
    Node* node = root;
    void* leaf = nullptr;
    while (true) {
      const int octant = node->octantOf(key);
      void* next = node->child[octant].load(std::memory_order_relaxed);
      if (next == nullptr) break;
      path.emplace_back(node, octant);
      if (node->height == 1) {
        leaf = next;
        break;
      }
      node = static_cast<Node*>(next);
    }
    if (leaf == nullptr) continue;
    doomed_blocks.insert(leaf);
    to_unlink.push_back(static_cast<VoxelBlock*>(leaf));
    for (auto it = path.rbegin(); it != path.rend(); ++it) {
      Node* n = it->first;
      n->child[it->second].store(nullptr, std::memory_order_release);
      const bool empty = std::all_of(
          n->child.begin(), n->child.end(),
          [](const std::atomic<void*>& c) { return c.load(std::memory_order_relaxed) == nullptr; });
      if (!empty) break;
      doomed_nodes.insert(n);
      if (n == root) root_.store(nullptr, std::memory_order_release);
    }
  }
  if (doomed_blocks.empty()) return 0;
  // All unlinked before any is freed: unlinking writes into neighbours, which may be doomed too.
  for (VoxelBlock* block : to_unlink) {
    unlink(block);
    free_rows_.push_back(block->row);
  }
  blocks_.erase(std::remove_if(blocks_.begin(), blocks_.end(),
                               [&](const VoxelBlock* b) { return doomed_blocks.count(b) > 0; }),
                blocks_.end());
  block_storage_.erase(std::remove_if(block_storage_.begin(), block_storage_.end(),
                                      [&](const std::unique_ptr<VoxelBlock>& b) {
                                        return doomed_blocks.count(b.get()) > 0;
                                      }),
                       block_storage_.end());
  nodes_.erase(std::remove_if(
                   nodes_.begin(), nodes_.end(),
                   [&](const std::unique_ptr<Node>& n) { return doomed_nodes.count(n.get()) > 0; }),
               nodes_.end());
  return doomed_blocks.size();
}

void BlockOctree::swap(BlockOctree& other) {
  if (this == &other) return;
  std::scoped_lock lock(alloc_mutex_, other.alloc_mutex_);
  // Neighbour links need no care: they point between blocks that change owner together.
  std::swap(block_size_m_, other.block_size_m_);
  Node* mine = root_.load(std::memory_order_relaxed);
  root_.store(other.root_.load(std::memory_order_relaxed), std::memory_order_release);
  other.root_.store(mine, std::memory_order_release);
  nodes_.swap(other.nodes_);
  blocks_.swap(other.blocks_);
  block_storage_.swap(other.block_storage_);
  free_rows_.swap(other.free_rows_);
  std::swap(row_count_, other.row_count_);
}

}  // namespace stereo_fusion
