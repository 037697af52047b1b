#include "stereo_fusion/map/BlockOctree.h"

#include <algorithm>
#include <cmath>

namespace stereo_fusion {

struct BlockOctree::Node {
  BlockKey origin;  // minimum corner, in blocks
  int height = 0;   // covers 2^height blocks per axis; children of height-1 nodes are blocks
  std::array<std::atomic<void*>, 8> child{};

  int32_t halfSide() const { return int32_t{1} << (height - 1); }
  BlockKey centre() const {
    const int32_t h = halfSide();
    return {origin.x + h, origin.y + h, origin.z + h};
  }
};

BlockOctree::BlockOctree(double block_size_m) : block_size_m_(block_size_m) {}
BlockOctree::~BlockOctree() = default;

BlockKey BlockOctree::keyForPoint(const Eigen::Vector3d& p_world) const {
  const Eigen::Vector3d k = (p_world / block_size_m_).array().floor();
  const double lim = static_cast<double>(kMaxKey) + 1.0;
  auto clampToInt = [lim](double v) {
    // Out-of-range (or NaN) coordinates map beyond kMaxKey so keyInRange() refuses them.
    if (!(std::abs(v) < lim)) return static_cast<int32_t>(kMaxKey) + 1;
    return static_cast<int32_t>(v);
  };
  return {clampToInt(k.x()), clampToInt(k.y()), clampToInt(k.z())};
}

Eigen::Vector3d BlockOctree::blockOrigin(const BlockKey& key) const {
  return Eigen::Vector3d(key.x, key.y, key.z) * block_size_m_;
}

bool BlockOctree::keyInRange(const BlockKey& key) {
  auto ok = [](int32_t v) { return v >= -kMaxKey && v <= kMaxKey; };
  return ok(key.x) && ok(key.y) && ok(key.z);
}

int BlockOctree::octantIndex(const BlockKey& key, const BlockKey& centre) {
  return 4 * (key.x >= centre.x) + 2 * (key.y >= centre.y) + (key.z >= centre.z);
}

bool BlockOctree::contains(const Node* node, const BlockKey& key) {
  // 64-bit arithmetic: origin + side may exceed int32 for the largest roots.
  const int64_t side = int64_t{1} << node->height;
  auto in = [side](int32_t o, int32_t v) {
    return int64_t{v} >= int64_t{o} && int64_t{v} < int64_t{o} + side;
  };
  return in(node->origin.x, key.x) && in(node->origin.y, key.y) && in(node->origin.z, key.z);
}

BlockOctree::Node* BlockOctree::newNode(const BlockKey& origin, int height) {
  nodes_.push_back(std::make_unique<Node>());
  Node* n = nodes_.back().get();
  n->origin = origin;
  n->height = height;
  return n;
}

VoxelBlock* BlockOctree::find(const BlockKey& key) const {
  searches_.fetch_add(1, std::memory_order_relaxed);
  const Node* node = root_.load(std::memory_order_acquire);
  if (node == nullptr || !contains(node, key)) return nullptr;
  while (true) {
    void* next = node->child[octantIndex(key, node->centre())].load(std::memory_order_acquire);
    if (next == nullptr) return nullptr;
    if (node->height == 1) return static_cast<VoxelBlock*>(next);
    node = static_cast<const Node*>(next);
  }
}

void BlockOctree::growToContain(const BlockKey& key) {
  Node* root = root_.load(std::memory_order_relaxed);
  if (root == nullptr) {
    // First block: a height-1 root covering the 2×2×2 blocks with the key at its lower corner
    // aligned to even coordinates, so the tree stays aligned to powers of two.
    auto align = [](int32_t v) { return static_cast<int32_t>(v & ~int32_t{1}); };
    root = newNode({align(key.x), align(key.y), align(key.z)}, 1);
    root_.store(root, std::memory_order_release);
  }
  while (!contains(root, key)) {
    // Double the root towards the key; the old root becomes one octant of the new one.
    // kMaxKey = 2^28 keeps every origin and side of this loop inside int32.
    const int32_t side = static_cast<int32_t>(int64_t{1} << root->height);
    BlockKey origin = root->origin;
    if (key.x < origin.x) origin.x -= side;
    if (key.y < origin.y) origin.y -= side;
    if (key.z < origin.z) origin.z -= side;
    Node* grown = newNode(origin, root->height + 1);
    grown->child[octantIndex(root->origin, grown->centre())].store(root,
                                                                  std::memory_order_relaxed);
    root_.store(grown, std::memory_order_release);
    root = grown;
  }
}

VoxelBlock* BlockOctree::findOrAllocate(const BlockKey& key, bool* allocated) {
  if (allocated) *allocated = false;
  if (!keyInRange(key)) return nullptr;
  if (VoxelBlock* existing = find(key)) return existing;

  std::lock_guard<std::mutex> lock(alloc_mutex_);
  growToContain(key);
  Node* node = root_.load(std::memory_order_relaxed);
  while (true) {
    std::atomic<void*>& slot = node->child[octantIndex(key, node->centre())];
    void* next = slot.load(std::memory_order_relaxed);
    if (node->height == 1) {
      if (next != nullptr) return static_cast<VoxelBlock*>(next);  // another thread won
      block_storage_.push_back(std::make_unique<VoxelBlock>());
      VoxelBlock* block = block_storage_.back().get();
      block->key = key;
      blocks_.push_back(block);
      slot.store(block, std::memory_order_release);
      if (allocated) *allocated = true;
      return block;
    }
    if (next == nullptr) {
      const int32_t h = node->halfSide();
      const BlockKey c = node->centre();
      const BlockKey child_origin{key.x >= c.x ? c.x : c.x - h, key.y >= c.y ? c.y : c.y - h,
                                  key.z >= c.z ? c.z : c.z - h};
      Node* child = newNode(child_origin, node->height - 1);
      slot.store(child, std::memory_order_release);
      next = child;
    }
    node = static_cast<Node*>(next);
  }
}

int BlockOctree::height() const {
  const Node* root = root_.load(std::memory_order_acquire);
  return root ? root->height : 0;
}

size_t BlockOctree::memoryBytes() const {
  return block_storage_.size() * sizeof(VoxelBlock) + nodes_.size() * sizeof(Node) +
         blocks_.capacity() * sizeof(VoxelBlock*) +
         block_storage_.capacity() * sizeof(std::unique_ptr<VoxelBlock>) +
         nodes_.capacity() * sizeof(std::unique_ptr<Node>);
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
}

}  // namespace stereo_fusion
