#pragma once
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include "stereo_fusion/map/BlockKey.h"
#include "stereo_fusion/paging/BlockStore.h"

namespace stereo_fusion {

/// Writes pages to the block store on a thread of its own, so that a page-out costs the frame
/// only the pages' encoding: a page handed over is readable (find()) until the store holds it
/// and the host has let it go (releaseWritten()), so the map never misses a block in between
/// nor reads an older page of it. The writer has its own connection to the store (SQLite's
/// write-ahead log lets the map read committed pages through its own meanwhile); the host
/// releases the written pages right before it begins a read snapshot, so every page it no
/// longer finds here is in that snapshot.
///
/// A write the store refuses (a full disk) stops the writer: that batch and every later one
/// stay readable through find() until the host brings their blocks back (failedKeys(),
/// forgetFailed()).
class PageWriter {
 public:
  using Page = std::shared_ptr<const std::vector<uint8_t>>;

  /// `store`: the writer's own connection (BlockStore::open() of the map's store file).
  explicit PageWriter(std::unique_ptr<BlockStore> store);
  /// Writes what is still pending, then ends the thread.
  ~PageWriter();
  PageWriter(const PageWriter&) = delete;
  PageWriter& operator=(const PageWriter&) = delete;

  /// Hands a batch over (one transaction in the store).
  void write(std::vector<BlockKey> keys, std::vector<Page> pages);
  /// Hands a checkpoint over (BlockStore::commit(), one transaction, after every batch before
  /// it); returns its batch number (written once writtenBatches() exceeds it).
  uint64_t commit(StoreCommit commit);
  /// Batches [0, this) are in the store.
  uint64_t writtenBatches() const;
  /// The page of `key` handed over and not released; nullptr when the store has it (or never
  /// had it).
  Page find(const BlockKey& key) const;
  /// Forgets the pages the store holds: from now on they are read from it. Call before a read
  /// snapshot of the store begins (a read transaction, or a single read outside one).
  void releaseWritten();
  /// Waits until every batch handed over is in the store (or refused).
  void flush();
  /// Bytes of the pages not released yet.
  size_t pendingBytes() const;
  /// After a refused write: the keys of every page the store does not hold, and why (false
  /// when no write failed).
  bool failedKeys(std::vector<BlockKey>* keys, std::string* error) const;
  /// The host brought the failed pages' blocks back: forget those pages; later batches are
  /// tried again.
  void forgetFailed();

 private:
  struct Batch {
    uint64_t id;
    std::vector<BlockKey> keys;
    std::vector<Page> pages;
    std::unique_ptr<StoreCommit> commit;  // a checkpoint: written by BlockStore::commit()
  };
  struct Pending {
    uint64_t batch;
    Page page;
  };
  void run();
  /// Queues `batch` with its pages readable through find() (mutex_ held).
  uint64_t queueLocked(Batch batch);

  std::unique_ptr<BlockStore> store_;
  mutable std::mutex mutex_;
  std::condition_variable work_;  // a batch came, or the end
  std::condition_variable done_;  // a batch left
  std::deque<Batch> batches_;
  std::unordered_map<BlockKey, Pending, BlockKeyHash> pending_;
  size_t pending_bytes_ = 0;
  uint64_t next_batch_ = 0;
  uint64_t written_batches_ = 0;  // batches [0, this) are in the store
  bool writing_ = false;          // the thread holds a batch
  bool failed_ = false;
  std::string error_;
  bool stop_ = false;
  std::thread thread_;  // last: starts once the rest is built
};

}  // namespace stereo_fusion
