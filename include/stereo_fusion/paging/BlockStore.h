#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "stereo_fusion/map/BlockKey.h"

struct sqlite3;
struct sqlite3_stmt;
struct ZSTD_CCtx_s;
struct ZSTD_DCtx_s;

namespace stereo_fusion {

/// One transaction of a map store (Mapper::checkpoint()): all of it or, after a kill or an
/// error, none.
struct StoreCommit {
  bool clear_first = false;     ///< drop every page first (a reset or a replaced map)
  std::vector<BlockKey> erase;  ///< blocks gone from the map
  std::vector<BlockKey> keys;   ///< pages written (or replaced)
  std::vector<std::shared_ptr<const std::vector<uint8_t>>> pages;
  std::vector<uint8_t> state;  ///< the checkpoint record (paging/CheckpointState.h)
};

/// What a store was made for: a store of another voxel grid is refused at open.
struct BlockStoreIdentity {
  double voxel_size_m = 0.0;
  double truncation_vox = 0.0;
};

/// The embedded store paged-out blocks live in: one SQLite database file (WAL journal), a page
/// (paging/BlockPage) per block key, zstd-compressed. SQLite was chosen by measurement
/// (doc/design.md, "Paging"): its reads go through a bounded page cache, so the process's RSS does
/// not grow with the store as it does with a memory-mapped store, a transaction is all or nothing
/// after a kill, and it starts no thread of its own.
///
/// Each write() is one transaction. Not thread-safe: the Mapper calls it under its map lock.
class BlockStore {
 public:
  /// Opens the database `file` (created, with its folder, if missing). A file that is not a
  /// stereo_fusion block store, or one made for another voxel grid, is refused with a sentence
  /// in `error` (nullptr returned); so is a folder that cannot be created or written.
  /// `durable`: every commit reaches the disk before it returns (synchronous=FULL), for the
  /// map store; a paging store only needs to survive its own process (NORMAL).
  static std::unique_ptr<BlockStore> open(const std::string& file,
                                          const BlockStoreIdentity& identity, std::string* error,
                                          bool durable = false);
  /// A store of its own for one map in `folder` (empty: the temporary folder), named
  /// pages-<pid>-<n>.sqlite, removed (with its journal) when the store is destroyed.
  static std::unique_ptr<BlockStore> openPrivate(const std::string& folder,
                                                 const BlockStoreIdentity& identity,
                                                 std::string* error);
  ~BlockStore();
  BlockStore(const BlockStore&) = delete;
  BlockStore& operator=(const BlockStore&) = delete;

  const std::string& file() const { return file_; }
  /// Writes (or replaces) the pages of `keys` in one transaction: all of them or, on an error
  /// (a full disk), none.
  bool write(const std::vector<BlockKey>& keys, const std::vector<std::vector<uint8_t>>& pages,
             std::string* error);
  bool write(const std::vector<BlockKey>& keys,
             const std::vector<const std::vector<uint8_t>*>& pages, std::string* error);
  /// The page of `key` into `page`. False with `error` empty when the store has none, with a
  /// sentence when it cannot be read.
  bool read(const BlockKey& key, std::vector<uint8_t>* page, std::string* error);
  /// Reads of many pages in one read transaction (one snapshot, one lock: a batch of reads
  /// costs about half as much as the same reads one by one). Nests: only the outer one counts.
  class ReadBatch {
   public:
    explicit ReadBatch(BlockStore* store);
    ~ReadBatch();

    ReadBatch(const ReadBatch&) = delete;
    ReadBatch& operator=(const ReadBatch&) = delete;

   private:
    BlockStore* store_;
    bool began_ = false;
  };
  /// Removes the pages of `keys` (missing ones are ignored), in one transaction.
  bool erase(const std::vector<BlockKey>& keys, std::string* error);
  /// Removes every page.
  bool clear(std::string* error);
  /// Writes `commit` in one transaction (the pages, the erasures and the checkpoint record).
  bool commit(const StoreCommit& commit, std::string* error);
  /// The checkpoint record of the last commit into `state`. False with `error` empty when the
  /// store has none (it was never checkpointed), with a sentence when it cannot be read.
  bool readState(std::vector<uint8_t>* state, std::string* error);
  /// Calls `visit` with every page in key order (one read transaction); stops and returns false
  /// when `visit` does, or with a sentence in `error` when the store cannot be read.
  bool eachPage(const std::function<bool(const BlockKey&, const uint8_t*, size_t)>& visit,
                std::string* error);
  /// Every key with a page, sorted.
  bool keys(std::vector<BlockKey>* out, std::string* error);

 private:
  BlockStore() = default;
  bool execute(const char* sql, std::string* error);
  /// Binds `page`, compressed, as `statement`'s 4th parameter.
  void bindPage(sqlite3_stmt* statement, const std::vector<uint8_t>& page);
  /// A stored page back to its bytes; false with a sentence when it does not decompress.
  bool unpack(const uint8_t* data, size_t size, std::vector<uint8_t>* page, std::string* error);
  /// Binds `key` (and `page`, when given) to `statement` and runs it once.
  bool stepKey(sqlite3_stmt* statement, const BlockKey& key, const std::vector<uint8_t>* page);
  bool prepare(const char* sql, sqlite3_stmt** statement, std::string* error);
  std::string failure(const std::string& what) const;
  /// Runs `statement` once per key (stepKey(), with `pages[i]` when given) in one transaction:
  /// all of them or, on an error, none.
  bool eachKeyInTransaction(const std::vector<BlockKey>& keys, sqlite3_stmt* statement,
                            const char* what, std::string* error,
                            const std::vector<const std::vector<uint8_t>*>* pages);

  std::string file_;
  bool remove_on_close_ = false;
  sqlite3* db_ = nullptr;
  sqlite3_stmt* insert_ = nullptr;
  sqlite3_stmt* select_ = nullptr;
  sqlite3_stmt* delete_ = nullptr;
  ZSTD_CCtx_s* compressor_ = nullptr;  // made on the first write
  ZSTD_DCtx_s* decompressor_ = nullptr;
  std::vector<uint8_t> packed_;  // the page being written, compressed
};

}  // namespace stereo_fusion
