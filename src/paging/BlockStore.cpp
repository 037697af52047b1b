#include "stereo_fusion/paging/BlockStore.h"

#include <sqlite3.h>
#include <zstd.h>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <filesystem>
#include <functional>
#include <system_error>

namespace stereo_fusion {

namespace {
// 2: pages zstd-compressed (1 held them raw).
constexpr const char* kFormat = "stereo_fusion block store 2";
// Fast: the writer thread compresses ~0.4 GB/s, and a voxel block's page shrinks ~2.3×, a
// submesh's ~1.6× (the building at 1 cm), so the disk the store shares writes half as much.
constexpr int kCompressionLevel = 1;

/// Runs `statement` to its end after binding `key` to its first three parameters.
void bindKey(sqlite3_stmt* statement, const BlockKey& key) {
  sqlite3_bind_int(statement, 1, key.x);
  sqlite3_bind_int(statement, 2, key.y);
  sqlite3_bind_int(statement, 3, key.z);
}

/// Ends a transaction that failed half-way: nothing of it stays.
void rollback(sqlite3* db) { sqlite3_exec(db, "ROLLBACK", nullptr, nullptr, nullptr); }
}  // namespace

std::unique_ptr<BlockStore> BlockStore::open(const std::string& file,
                                             const BlockStoreIdentity& identity, std::string* error,
                                             bool durable) {
  std::unique_ptr<BlockStore> store(new BlockStore());
  store->file_ = file;
  const std::filesystem::path parent = std::filesystem::path(file).parent_path();
  std::error_code ec;
  if (!parent.empty()) std::filesystem::create_directories(parent, ec);
  if (ec) {
    *error = file + ": cannot create the store's folder (" + ec.message() + ")";
    return nullptr;
  }
  if (sqlite3_open_v2(file.c_str(), &store->db_,
                      SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX,
                      nullptr) != SQLITE_OK) {
    *error = store->failure("cannot open the block store");
    return nullptr;
  }
  sqlite3_busy_timeout(store->db_, 2000);
  // WAL: a commit appends to the log, readers see the last commit, and a killed process leaves
  // the database at its last commit. NORMAL syncs at checkpoints, not at every commit: paged
  // blocks are a cache of the map in memory until the store is made durable (save).
  // A file that is not a database fails on its first read: here.
  if (!store->execute("PRAGMA journal_mode=WAL", error) ||
      !store->execute(durable ? "PRAGMA synchronous=FULL" : "PRAGMA synchronous=NORMAL", error) ||
      !store->execute("PRAGMA cache_size=-8192", error) ||  // 8 MiB, whatever the store's size
      !store->execute("CREATE TABLE IF NOT EXISTS meta(name TEXT PRIMARY KEY, value) ", error) ||
      !store->execute("CREATE TABLE IF NOT EXISTS pages(x INTEGER NOT NULL, y INTEGER NOT NULL, "
                      "z INTEGER NOT NULL, page BLOB NOT NULL, PRIMARY KEY(x, y, z))",
                      error)) {
    *error = file + ": not a stereo_fusion block store, or unreadable (" + *error + ")";
    return nullptr;
  }
  sqlite3_stmt* meta = nullptr;
  if (!store->prepare("SELECT name, value FROM meta", &meta, error)) return nullptr;
  std::string format;
  double voxel = 0.0, truncation = 0.0;
  int rows = 0;
  while (sqlite3_step(meta) == SQLITE_ROW) {
    ++rows;
    const std::string name = reinterpret_cast<const char*>(sqlite3_column_text(meta, 0));
    if (name == "format" && sqlite3_column_type(meta, 1) == SQLITE_TEXT)
      format = reinterpret_cast<const char*>(sqlite3_column_text(meta, 1));
    if (name == "voxel_size_m") voxel = sqlite3_column_double(meta, 1);
    if (name == "truncation_vox") truncation = sqlite3_column_double(meta, 1);
  }
  sqlite3_finalize(meta);
  if (rows == 0) {
    sqlite3_stmt* put = nullptr;
    if (!store->prepare("INSERT INTO meta(name, value) VALUES ('format', ?1), "
                        "('voxel_size_m', ?2), ('truncation_vox', ?3)",
                        &put, error))
      return nullptr;
    sqlite3_bind_text(put, 1, kFormat, -1, SQLITE_STATIC);
    sqlite3_bind_double(put, 2, identity.voxel_size_m);
    sqlite3_bind_double(put, 3, identity.truncation_vox);
    const int rc = sqlite3_step(put);
    sqlite3_finalize(put);
    if (rc != SQLITE_DONE) {
      *error = store->failure("cannot write the block store");
      return nullptr;
    }
  } else if (format != kFormat) {
    *error = file + ": not a stereo_fusion block store (format '" + format + "')";
    return nullptr;
  } else if (voxel != identity.voxel_size_m || truncation != identity.truncation_vox) {
    *error = file + ": the store holds a map of voxel_size_m " + std::to_string(voxel) +
             ", truncation_vox " + std::to_string(truncation) + ", this mapper uses " +
             std::to_string(identity.voxel_size_m) + ", " + std::to_string(identity.truncation_vox);
    return nullptr;
  }
  if (!store->prepare("INSERT OR REPLACE INTO pages(x, y, z, page) VALUES (?1, ?2, ?3, ?4)",
                      &store->insert_, error) ||
      !store->prepare("SELECT page FROM pages WHERE x = ?1 AND y = ?2 AND z = ?3", &store->select_,
                      error) ||
      !store->prepare("DELETE FROM pages WHERE x = ?1 AND y = ?2 AND z = ?3", &store->delete_,
                      error))
    return nullptr;
  return store;
}

std::unique_ptr<BlockStore> BlockStore::openPrivate(const std::string& folder,
                                                    const BlockStoreIdentity& identity,
                                                    std::string* error) {
  static std::atomic<uint64_t> counter{0};
  std::error_code ec;
  const std::filesystem::path dir =
      folder.empty() ? std::filesystem::temp_directory_path(ec) : std::filesystem::path(folder);
  const std::string name = "pages-" + std::to_string(::getpid()) + "-" +
                           std::to_string(counter.fetch_add(1)) + ".sqlite";
  const std::string file = (dir / name).string();
  // A file left by an earlier process of the same pid (killed) is not this map's.
  for (const char* suffix : {"", "-wal", "-shm"}) std::filesystem::remove(file + suffix, ec);
  std::unique_ptr<BlockStore> store = open(file, identity, error);
  if (store) store->remove_on_close_ = true;
  return store;
}

BlockStore::~BlockStore() {
  ZSTD_freeCCtx(compressor_);
  ZSTD_freeDCtx(decompressor_);
  sqlite3_finalize(insert_);
  sqlite3_finalize(select_);
  sqlite3_finalize(delete_);
  if (db_) sqlite3_close_v2(db_);
  if (!remove_on_close_) return;
  std::error_code ec;
  for (const char* suffix : {"", "-wal", "-shm"}) std::filesystem::remove(file_ + suffix, ec);
}

std::string BlockStore::failure(const std::string& what) const {
  return file_ + ": " + what + " (" + (db_ ? sqlite3_errmsg(db_) : "out of memory") + ")";
}

bool BlockStore::execute(const char* sql, std::string* error) {
  char* message = nullptr;
  if (sqlite3_exec(db_, sql, nullptr, nullptr, &message) == SQLITE_OK) return true;
  *error = file_ + ": " + (message ? message : "unknown error");
  sqlite3_free(message);
  return false;
}

bool BlockStore::prepare(const char* sql, sqlite3_stmt** statement, std::string* error) {
  if (sqlite3_prepare_v2(db_, sql, -1, statement, nullptr) == SQLITE_OK) return true;
  *error = failure("cannot read the block store");
  return false;
}

bool BlockStore::write(const std::vector<BlockKey>& keys,
                       const std::vector<std::vector<uint8_t>>& pages, std::string* error) {
  std::vector<const std::vector<uint8_t>*> pointers;
  for (const std::vector<uint8_t>& page : pages) pointers.push_back(&page);
  return write(keys, pointers, error);
}

bool BlockStore::write(const std::vector<BlockKey>& keys,
                       const std::vector<const std::vector<uint8_t>*>& pages, std::string* error) {
  return eachKeyInTransaction(keys, insert_, "cannot write pages", error, &pages);
}

bool BlockStore::eachKeyInTransaction(const std::vector<BlockKey>& keys, sqlite3_stmt* statement,
                                      const char* what, std::string* error,
                                      const std::vector<const std::vector<uint8_t>*>* pages) {
  if (keys.empty()) return true;
  if (!execute("BEGIN", error)) return false;
  for (size_t i = 0; i < keys.size(); ++i) {
    if (!stepKey(statement, keys[i], pages ? (*pages)[i] : nullptr)) {
      *error = failure(what);
      rollback(db_);
      return false;
    }
  }
  if (execute("COMMIT", error)) return true;
  rollback(db_);
  return false;
}

bool BlockStore::read(const BlockKey& key, std::vector<uint8_t>* page, std::string* error) {
  error->clear();
  bindKey(select_, key);
  const int rc = sqlite3_step(select_);
  bool found = false;
  if (rc == SQLITE_ROW) {
    const auto* data = static_cast<const uint8_t*>(sqlite3_column_blob(select_, 0));
    const int bytes = sqlite3_column_bytes(select_, 0);
    found = unpack(data, static_cast<size_t>(bytes), page, error);
  } else if (rc != SQLITE_DONE) {
    *error = failure("cannot read a page");
  }
  sqlite3_reset(select_);
  return found;
}

BlockStore::ReadBatch::ReadBatch(BlockStore* store) : store_(store) {
  // Inside a transaction already (autocommit off): that one is the batch.
  if (sqlite3_get_autocommit(store_->db_) == 0) return;
  began_ = sqlite3_exec(store_->db_, "BEGIN", nullptr, nullptr, nullptr) == SQLITE_OK;
}

BlockStore::ReadBatch::~ReadBatch() {
  if (began_) sqlite3_exec(store_->db_, "COMMIT", nullptr, nullptr, nullptr);
}

bool BlockStore::erase(const std::vector<BlockKey>& keys, std::string* error) {
  return eachKeyInTransaction(keys, delete_, "cannot erase pages", error, nullptr);
}

void BlockStore::bindPage(sqlite3_stmt* statement, const std::vector<uint8_t>& page) {
  if (!compressor_) compressor_ = ZSTD_createCCtx();
  packed_.resize(ZSTD_compressBound(page.size()));
  const size_t packed = ZSTD_compressCCtx(compressor_, packed_.data(), packed_.size(), page.data(),
                                          page.size(), kCompressionLevel);
  // Cannot fail with a buffer of compressBound() bytes but for lack of memory: then raw, which
  // the reader refuses as it refuses any corrupted page.
  packed_.resize(ZSTD_isError(packed) ? 0 : packed);
  static const uint8_t kNothing = 0;  // a null data() would be stored as NULL
  sqlite3_bind_blob64(statement, 4, packed_.empty() ? &kNothing : packed_.data(), packed_.size(),
                      SQLITE_STATIC);  // stepped before packed_ changes
}

bool BlockStore::unpack(const uint8_t* data, size_t size, std::vector<uint8_t>* page,
                        std::string* error) {
  const unsigned long long bytes = ZSTD_getFrameContentSize(data, size);
  if (bytes == ZSTD_CONTENTSIZE_ERROR || bytes == ZSTD_CONTENTSIZE_UNKNOWN ||
      bytes > (uint64_t{1} << 31)) {
    *error = file_ + ": a page is not a compressed page (corrupted store)";
    return false;
  }
  if (!decompressor_) decompressor_ = ZSTD_createDCtx();
  page->resize(bytes);
  const size_t unpacked =
      ZSTD_decompressDCtx(decompressor_, page->data(), page->size(), data, size);
  if (ZSTD_isError(unpacked) || unpacked != bytes) {
    *error = file_ + ": a page does not decompress (" +
             (ZSTD_isError(unpacked) ? ZSTD_getErrorName(unpacked) : "short") +
             "; corrupted store)";
    return false;
  }
  return true;
}

bool BlockStore::stepKey(sqlite3_stmt* statement, const BlockKey& key,
                         const std::vector<uint8_t>* page) {
  bindKey(statement, key);
  if (page) bindPage(statement, *page);
  const int rc = sqlite3_step(statement);
  sqlite3_reset(statement);
  return rc == SQLITE_DONE;
}

bool BlockStore::commit(const StoreCommit& commit, std::string* error) {
  if (!execute("BEGIN", error)) return false;
  bool ok = !commit.clear_first || execute("DELETE FROM pages", error);
  for (size_t i = 0; ok && i < commit.erase.size(); ++i)
    ok = stepKey(delete_, commit.erase[i], nullptr);
  for (size_t i = 0; ok && i < commit.keys.size(); ++i)
    ok = stepKey(insert_, commit.keys[i], commit.pages[i].get());
  if (ok) {
    sqlite3_stmt* put = nullptr;
    ok = prepare("INSERT OR REPLACE INTO meta(name, value) VALUES ('checkpoint', ?1)", &put, error);
    if (ok) {
      sqlite3_bind_blob64(put, 1, commit.state.data(), commit.state.size(), SQLITE_STATIC);
      ok = sqlite3_step(put) == SQLITE_DONE;
      sqlite3_finalize(put);
    }
  }
  if (!ok) {
    if (error->empty()) *error = failure("cannot write the checkpoint");
    rollback(db_);
    return false;
  }
  if (execute("COMMIT", error)) return true;
  rollback(db_);
  return false;
}

bool BlockStore::readState(std::vector<uint8_t>* state, std::string* error) {
  error->clear();
  sqlite3_stmt* get = nullptr;
  if (!prepare("SELECT value FROM meta WHERE name = 'checkpoint'", &get, error)) return false;
  const int rc = sqlite3_step(get);
  bool found = false;
  if (rc == SQLITE_ROW && sqlite3_column_type(get, 0) == SQLITE_BLOB) {
    const auto* data = static_cast<const uint8_t*>(sqlite3_column_blob(get, 0));
    state->assign(data, data + sqlite3_column_bytes(get, 0));
    found = true;
  } else if (rc == SQLITE_ROW) {
    *error = file_ + ": its checkpoint record is not a blob";
  } else if (rc != SQLITE_DONE) {
    *error = failure("cannot read the checkpoint record");
  }
  sqlite3_finalize(get);
  return found;
}

bool BlockStore::eachPage(const std::function<bool(const BlockKey&, const uint8_t*, size_t)>& visit,
                          std::string* error) {
  error->clear();
  sqlite3_stmt* all = nullptr;
  if (!prepare("SELECT x, y, z, page FROM pages ORDER BY z, y, x", &all, error)) return false;
  ReadBatch batch(this);
  int rc;
  bool visited_all = true;
  std::vector<uint8_t> page;
  while ((rc = sqlite3_step(all)) == SQLITE_ROW) {
    const BlockKey key{sqlite3_column_int(all, 0), sqlite3_column_int(all, 1),
                       sqlite3_column_int(all, 2)};
    const auto* data = static_cast<const uint8_t*>(sqlite3_column_blob(all, 3));
    if (!unpack(data, static_cast<size_t>(sqlite3_column_bytes(all, 3)), &page, error) ||
        !visit(key, page.data(), page.size())) {
      visited_all = false;
      break;
    }
  }
  sqlite3_finalize(all);
  if (visited_all && rc != SQLITE_DONE) {
    *error = failure("cannot read the pages");
    return false;
  }
  return visited_all;
}

bool BlockStore::clear(std::string* error) { return execute("DELETE FROM pages", error); }

bool BlockStore::keys(std::vector<BlockKey>* out, std::string* error) {
  sqlite3_stmt* all = nullptr;
  if (!prepare("SELECT x, y, z FROM pages ORDER BY z, y, x", &all, error)) return false;
  out->clear();
  int rc;
  while ((rc = sqlite3_step(all)) == SQLITE_ROW)
    out->push_back(
        {sqlite3_column_int(all, 0), sqlite3_column_int(all, 1), sqlite3_column_int(all, 2)});
  sqlite3_finalize(all);
  if (rc != SQLITE_DONE) {
    *error = failure("cannot list the pages");
    return false;
  }
  return true;
}

}  // namespace stereo_fusion
