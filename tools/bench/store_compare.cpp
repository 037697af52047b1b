// store_compare: a like-for-like benchmark of three embedded key-value stores (LMDB, RocksDB,
// SQLite) for paging TSDF map blocks out to disk and back. Standalone C++17, no ROS.
//
//   g++ -std=c++17 -O2 -I.. store_compare.cpp -o store_compare -llmdb -lrocksdb -lsqlite3 -lzstd
//   ./store_compare [--blocks N] [--crash-runs R] [--configs a,b,...] [--no-crash] DIR
// (-I..: tools/cli/, the tools' command-line helpers on CLI11, Debian's libcli11-dev.)
//
// Every configuration runs in a fresh process (exec of itself), so VmHWM, RssFile, RssAnon and the
// thread count are that store's alone. Results go to DIR/results.txt and, as markdown tables, to
// stdout. tools/bench/store_compare.md holds the results and the reasoning.
//
// Workload (see store_compare.md): values are map-file records (io/MapFile.h, version 3): a 24-byte
// head (i32 x, y, z; u64 last update frame; u8 level mask; 3 zero bytes) followed by the stored
// levels' voxels (f32 sdf, f32 weight, u8 r, g, b, 0). 30 % of blocks hold only the 2^3 level
// (120 B), 40 % the 4^3 and 2^3 levels (888 B), 30 % all three (7032 B). Keys are 12 bytes: x, y, z
// as int32 with the sign bit flipped, big-endian, so byte order is (x, y, z) order. A page-out
// batch is 500 blocks (a 10x10x5 chunk of a 200x100x10-block map, chunks in random order) plus a
// batch counter key, in one durable transaction.
#include <cerrno>
#include <fcntl.h>
#include <lmdb.h>
#include <signal.h>
#include <sqlite3.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zstd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <dirent.h>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include <rocksdb/cache.h>
#include <rocksdb/db.h>
#include <rocksdb/filter_policy.h>
#include <rocksdb/options.h>
#include <rocksdb/table.h>
#include <rocksdb/write_batch.h>

#include "cli/CommandLine.h"
#include "cli/NumberChecks.h"

namespace {

// ---------------------------------------------------------------------------------------------
// Small helpers

[[noreturn]] void die(const std::string& what) {
  std::fprintf(stderr, "store_compare: %s\n", what.c_str());
  std::exit(2);
}

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}
double usSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
}
// This thread's CPU time, µs: a latency without preemption and I/O waits (the machine is shared).
double threadCpuUs() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e6 + static_cast<double>(ts.tv_nsec) / 1e3;
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  size_t i = static_cast<size_t>(std::ceil(p * static_cast<double>(v.size())));
  if (i > 0) --i;
  return v[std::min(i, v.size() - 1)];
}

uint64_t splitmix(uint64_t& s) {
  uint64_t z = (s += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

struct ProcStatus {
  long hwm_kb = 0, rss_kb = 0, anon_kb = 0, file_kb = 0, shmem_kb = 0, threads = 0;
};
ProcStatus readStatus() {
  ProcStatus s;
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line)) {
    auto num = [&](const char* tag, long* out) {
      if (line.rfind(tag, 0) == 0) *out = std::atol(line.c_str() + std::strlen(tag));
    };
    num("VmHWM:", &s.hwm_kb);
    num("VmRSS:", &s.rss_kb);
    num("RssAnon:", &s.anon_kb);
    num("RssFile:", &s.file_kb);
    num("RssShmem:", &s.shmem_kb);
    num("Threads:", &s.threads);
  }
  return s;
}
double loadAverage() {
  double l = 0;
  std::ifstream("/proc/loadavg") >> l;
  return l;
}
void resetPeakRss() {
  int fd = ::open("/proc/self/clear_refs", O_WRONLY);
  if (fd >= 0) {
    if (::write(fd, "5", 1) != 1) {
    }
    ::close(fd);
  }
}

std::vector<std::string> listFiles(const std::string& dir) {
  std::vector<std::string> out;
  if (DIR* d = ::opendir(dir.c_str())) {
    while (dirent* e = ::readdir(d)) {
      std::string n = e->d_name;
      if (n == "." || n == "..") continue;
      std::string p = dir + "/" + n;
      struct stat st;
      if (::stat(p.c_str(), &st) == 0) {
        if (S_ISDIR(st.st_mode)) {
          for (auto& q : listFiles(p)) out.push_back(q);
        } else {
          out.push_back(p);
        }
      }
    }
    ::closedir(d);
  }
  return out;
}
// Allocated bytes (st_blocks) of every file under dir.
uint64_t diskBytes(const std::string& dir) {
  uint64_t sum = 0;
  for (auto& p : listFiles(dir)) {
    struct stat st;
    if (::stat(p.c_str(), &st) == 0) sum += static_cast<uint64_t>(st.st_blocks) * 512;
  }
  return sum;
}
// Drops the store's files from the page cache (no effect on tmpfs).
void evictFromPageCache(const std::string& dir) {
  for (auto& p : listFiles(dir)) {
    int fd = ::open(p.c_str(), O_RDONLY);
    if (fd < 0) continue;
    ::fdatasync(fd);
    ::posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED);
    ::close(fd);
  }
}
void removeTree(const std::string& dir) {
  std::string cmd = "rm -rf '" + dir + "'";
  if (std::system(cmd.c_str()) != 0) die("cannot remove " + dir);
}
void makeDir(const std::string& dir) {
  std::string cmd = "mkdir -p '" + dir + "'";
  if (std::system(cmd.c_str()) != 0) die("cannot create " + dir);
}

// ---------------------------------------------------------------------------------------------
// Keys and values

std::string encodeKey(int32_t x, int32_t y, int32_t z) {
  std::string k(12, '\0');
  const int32_t c[3] = {x, y, z};
  for (int i = 0; i < 3; ++i) {
    uint32_t u = static_cast<uint32_t>(c[i]) ^ 0x80000000u;
    k[4 * i + 0] = static_cast<char>(u >> 24);
    k[4 * i + 1] = static_cast<char>(u >> 16);
    k[4 * i + 2] = static_cast<char>(u >> 8);
    k[4 * i + 3] = static_cast<char>(u);
  }
  return k;
}
// The batch counter: a 7-byte key, so it never collides with a 12-byte block key.
const std::string kCounterKey(
    "\xff\xff\xff\xff"
    "cnt",
    7);
std::string encodeCounter(uint64_t c) {
  std::string v(8, '\0');
  for (int i = 0; i < 8; ++i) v[i] = static_cast<char>(c >> (56 - 8 * i));
  return v;
}
uint64_t decodeCounter(const uint8_t* p, size_t n) {
  if (n != 8) return 0;
  uint64_t c = 0;
  for (int i = 0; i < 8; ++i) c = (c << 8) | p[i];
  return c;
}

template <typename T>
void append(std::string& s, T v) {
  s.append(reinterpret_cast<const char*>(&v), sizeof v);
}

// One block as the map file stores it. Deterministic in (x, y, z, seed).
// Surface: a plane across the block along one axis, sdf a ramp clamped to +-truncation with
// noise in the low mantissa bits; voxels further than the truncation behind it unobserved
// (weight 0); weights a few equal small integers; colours from a 4-colour palette in runs.
std::string makeBlock(int32_t x, int32_t y, int32_t z, uint64_t seed) {
  uint64_t s = seed ^ (static_cast<uint64_t>(static_cast<uint32_t>(x)) * 0x9E3779B97F4A7C15ull) ^
               (static_cast<uint64_t>(static_cast<uint32_t>(y)) * 0xC2B2AE3D27D4EB4Full) ^
               (static_cast<uint64_t>(static_cast<uint32_t>(z)) * 0x165667B19E3779F9ull);
  splitmix(s);
  const uint64_t h = splitmix(s);
  const int cls = static_cast<int>(h % 10);
  const uint8_t mask = cls < 3 ? 0x4 : (cls < 7 ? 0x6 : 0x7);  // bit l: level l (0 = 8^3)
  std::string out;
  out.reserve(24 + 584 * 12);
  append<int32_t>(out, x);
  append<int32_t>(out, y);
  append<int32_t>(out, z);
  append<uint64_t>(out, 1000 + (h >> 8) % 50000);
  out.push_back(static_cast<char>(mask));
  out.append(3, '\0');

  const int axis = static_cast<int>((h >> 4) % 3);
  const float offset = static_cast<float>(splitmix(s) % 1000) / 1000.0f;  // surface position
  const float base_weight = static_cast<float>(1 + splitmix(s) % 12);
  uint8_t palette[4][3];
  for (auto& c : palette) {
    uint64_t r = splitmix(s);
    c[0] = static_cast<uint8_t>(r);
    c[1] = static_cast<uint8_t>(r >> 8);
    c[2] = static_cast<uint8_t>(r >> 16);
  }
  for (int level = 0; level < 3; ++level) {
    if (!(mask & (1 << level))) continue;
    const int side = 8 >> level;
    const float vs = 0.02f * static_cast<float>(1 << level);  // voxel edge of this level, m
    const float trunc = 4.0f * vs;
    for (int k = 0; k < side; ++k)
      for (int j = 0; j < side; ++j)
        for (int i = 0; i < side; ++i) {
          const int c[3] = {i, j, k};
          const float d =
              (offset * static_cast<float>(side) - static_cast<float>(c[axis])) * vs + 0.3f * trunc;
          float sdf = 0, w = 0;
          uint8_t rgb[3] = {0, 0, 0};
          if (d >= -trunc) {
            sdf = std::min(d, trunc);
            uint32_t bits;
            std::memcpy(&bits, &sdf, 4);
            bits ^= static_cast<uint32_t>(splitmix(s)) & 0x3FFu;  // noise in the low 10 bits
            std::memcpy(&sdf, &bits, 4);
            const uint64_t r = splitmix(s);
            w = base_weight - static_cast<float>((r % 10) < 2 ? 1 + (r >> 8) % 2 : 0);
            if (w < 1) w = 1;
            const int p = ((i + j) / 2 + static_cast<int>((r >> 16) % 8 == 0)) % 4;
            std::memcpy(rgb, palette[p], 3);
          }
          append<float>(out, sdf);
          append<float>(out, w);
          out.push_back(static_cast<char>(rgb[0]));
          out.push_back(static_cast<char>(rgb[1]));
          out.push_back(static_cast<char>(rgb[2]));
          out.push_back('\0');
        }
  }
  return out;
}

struct Codec {
  int level = 0;  // 0: stored raw
  ZSTD_CCtx* c = ZSTD_createCCtx();
  ZSTD_DCtx* d = ZSTD_createDCtx();
  ~Codec() {
    ZSTD_freeCCtx(c);
    ZSTD_freeDCtx(d);
  }
  void encode(const std::string& raw, std::string& out) {
    if (level == 0) {
      out = raw;
      return;
    }
    out.resize(ZSTD_compressBound(raw.size()));
    size_t n = ZSTD_compressCCtx(c, &out[0], out.size(), raw.data(), raw.size(), level);
    if (ZSTD_isError(n)) die("zstd compress");
    out.resize(n);
  }
  // Materialises the raw block (the caller's VoxelBlock would be filled from it).
  bool decode(const uint8_t* p, size_t n, std::string& raw) {
    if (level == 0) {
      raw.assign(reinterpret_cast<const char*>(p), n);
      return true;
    }
    unsigned long long sz = ZSTD_getFrameContentSize(p, n);
    if (sz == ZSTD_CONTENTSIZE_ERROR || sz == ZSTD_CONTENTSIZE_UNKNOWN || sz > (1u << 20))
      return false;
    raw.resize(sz);
    size_t got = ZSTD_decompressDCtx(d, &raw[0], raw.size(), p, n);
    return !ZSTD_isError(got) && got == sz;
  }
};

// ---------------------------------------------------------------------------------------------
// Stores

using Sink = std::function<void(const uint8_t*, size_t)>;
using KV = std::pair<std::string, std::string>;

struct Store {
  virtual ~Store() = default;
  virtual void open(const std::string& dir) = 0;
  virtual void close() = 0;
  // One durable transaction (keys sorted).
  virtual void putBatch(const std::vector<KV>& kv) = 0;
  virtual void eraseBatch(const std::vector<std::string>& keys) = 0;
  virtual bool get(const std::string& key, const Sink& sink) = 0;
  // A spatial cluster of sorted keys in one read transaction / call; returns how many found.
  virtual size_t getMany(const std::vector<std::string>& keys, const Sink& sink) = 0;
  // Every key in order; fn(key, keylen, value, valuelen).
  virtual uint64_t scan(
      const std::function<void(const char*, size_t, const uint8_t*, size_t)>&) = 0;
  // The store's own integrity check after reopening ("" when fine).
  virtual std::string check() = 0;
  uint64_t counter() {
    uint64_t c = 0;
    get(kCounterKey, [&](const uint8_t* p, size_t n) { c = decodeCounter(p, n); });
    return c;
  }
};

// SQLite in WAL mode, one WITHOUT ROWID table keyed by the 12-byte blob (optionally another
// page size, or a rowid table whose BLOB PRIMARY KEY is a separate index).
class SqliteStore : public Store {
 public:
  explicit SqliteStore(bool full_sync, int page_size = 0, bool rowid = false)
      : full_(full_sync), page_size_(page_size), rowid_(rowid) {}
  ~SqliteStore() override { close(); }
  void open(const std::string& dir) override {
    const std::string path = dir + "/blocks.sqlite";
    if (sqlite3_open_v2(path.c_str(), &db_,
                        SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX,
                        nullptr) != SQLITE_OK)
      die("sqlite open");
    if (page_size_) exec(("PRAGMA page_size=" + std::to_string(page_size_)).c_str());
    exec("PRAGMA journal_mode=WAL");
    exec(full_ ? "PRAGMA synchronous=FULL" : "PRAGMA synchronous=NORMAL");
    exec(rowid_ ? "CREATE TABLE IF NOT EXISTS blocks(k BLOB PRIMARY KEY, v BLOB NOT NULL)"
                : "CREATE TABLE IF NOT EXISTS blocks(k BLOB PRIMARY KEY, v BLOB NOT NULL) WITHOUT "
                  "ROWID");
    ins_ = prep("INSERT OR REPLACE INTO blocks(k, v) VALUES(?1, ?2)");
    sel_ = prep("SELECT v FROM blocks WHERE k = ?1");
    del_ = prep("DELETE FROM blocks WHERE k = ?1");
    begin_ = prep("BEGIN");
    commit_ = prep("COMMIT");
    scan_ = prep("SELECT k, v FROM blocks ORDER BY k");
  }
  void close() override {
    for (sqlite3_stmt** s : {&ins_, &sel_, &del_, &begin_, &commit_, &scan_}) {
      if (*s) sqlite3_finalize(*s);
      *s = nullptr;
    }
    if (db_) sqlite3_close(db_);
    db_ = nullptr;
  }
  void putBatch(const std::vector<KV>& kv) override {
    step(begin_);
    for (auto& e : kv) {
      sqlite3_bind_blob(ins_, 1, e.first.data(), static_cast<int>(e.first.size()), SQLITE_STATIC);
      sqlite3_bind_blob(ins_, 2, e.second.data(), static_cast<int>(e.second.size()), SQLITE_STATIC);
      step(ins_);
    }
    step(commit_);
  }
  void eraseBatch(const std::vector<std::string>& keys) override {
    step(begin_);
    for (auto& k : keys) {
      sqlite3_bind_blob(del_, 1, k.data(), static_cast<int>(k.size()), SQLITE_STATIC);
      step(del_);
    }
    step(commit_);
  }
  bool get(const std::string& key, const Sink& sink) override {
    sqlite3_bind_blob(sel_, 1, key.data(), static_cast<int>(key.size()), SQLITE_STATIC);
    int rc = sqlite3_step(sel_);
    bool found = rc == SQLITE_ROW;
    if (found)
      sink(static_cast<const uint8_t*>(sqlite3_column_blob(sel_, 0)),
           static_cast<size_t>(sqlite3_column_bytes(sel_, 0)));
    else if (rc != SQLITE_DONE)
      die(std::string("sqlite get: ") + sqlite3_errmsg(db_));
    sqlite3_reset(sel_);
    return found;
  }
  size_t getMany(const std::vector<std::string>& keys, const Sink& sink) override {
    step(begin_);
    size_t n = 0;
    for (auto& k : keys) n += get(k, sink);
    step(commit_);
    return n;
  }
  uint64_t scan(
      const std::function<void(const char*, size_t, const uint8_t*, size_t)>& fn) override {
    uint64_t n = 0;
    int rc;
    while ((rc = sqlite3_step(scan_)) == SQLITE_ROW) {
      fn(static_cast<const char*>(sqlite3_column_blob(scan_, 0)),
         static_cast<size_t>(sqlite3_column_bytes(scan_, 0)),
         static_cast<const uint8_t*>(sqlite3_column_blob(scan_, 1)),
         static_cast<size_t>(sqlite3_column_bytes(scan_, 1)));
      ++n;
    }
    if (rc != SQLITE_DONE) die("sqlite scan");
    sqlite3_reset(scan_);
    return n;
  }
  std::string check() override {
    sqlite3_stmt* s = prep("PRAGMA integrity_check");
    std::string out;
    while (sqlite3_step(s) == SQLITE_ROW) {
      std::string row = reinterpret_cast<const char*>(sqlite3_column_text(s, 0));
      if (row != "ok") out += row + "; ";
    }
    sqlite3_finalize(s);
    return out;
  }

 private:
  void exec(const char* sql) {
    char* err = nullptr;
    if (sqlite3_exec(db_, sql, nullptr, nullptr, &err) != SQLITE_OK)
      die(std::string("sqlite: ") + sql + ": " + (err ? err : "?"));
  }
  sqlite3_stmt* prep(const char* sql) {
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(db_, sql, -1, &s, nullptr) != SQLITE_OK)
      die(std::string("sqlite prepare: ") + sql);
    return s;
  }
  void step(sqlite3_stmt* s) {
    int rc = sqlite3_step(s);
    if (rc != SQLITE_DONE && rc != SQLITE_ROW) die(std::string("sqlite: ") + sqlite3_errmsg(db_));
    sqlite3_reset(s);
  }
  bool full_;
  int page_size_;
  bool rowid_;
  sqlite3* db_ = nullptr;
  sqlite3_stmt *ins_ = nullptr, *sel_ = nullptr, *del_ = nullptr, *begin_ = nullptr,
               *commit_ = nullptr, *scan_ = nullptr;
};

// LMDB with default (synchronous) commits. Optionally MDB_NORDAHEAD, and optionally dropping the
// map's page-table entries with madvise(MADV_DONTNEED) whenever the process's file-backed RSS
// passes 32 MB, which bounds the RssFile that touching the mapped file adds (the pages stay in
// the page cache; only this process's mapping of them goes).
class LmdbStore : public Store {
 public:
  LmdbStore(bool nordahead, bool madv) : nordahead_(nordahead), madv_(madv) {}
  ~LmdbStore() override { close(); }
  void open(const std::string& dir) override {
    check(mdb_env_create(&env_), "env_create");
    check(mdb_env_set_mapsize(env_, size_t(64) << 30), "set_mapsize");
    unsigned flags = MDB_NOTLS | (nordahead_ ? MDB_NORDAHEAD : 0);
    check(mdb_env_open(env_, dir.c_str(), flags, 0644), "env_open");
    MDB_txn* t;
    check(mdb_txn_begin(env_, nullptr, 0, &t), "txn_begin");
    check(mdb_dbi_open(t, nullptr, 0, &dbi_), "dbi_open");
    check(mdb_txn_commit(t), "commit");
    check(mdb_txn_begin(env_, nullptr, MDB_RDONLY, &rtxn_), "rtxn");
    mdb_txn_reset(rtxn_);
    mdb_env_get_fd(env_, &fd_);
    // mdb_env_info()'s me_mapaddr is only set with MDB_FIXEDMAP: find the map in /proc/self/maps.
    struct stat st;
    ::fstat(fd_, &st);
    std::ifstream maps("/proc/self/maps");
    std::string line;
    while (std::getline(maps, line)) {
      unsigned long lo = 0, hi = 0, off = 0, ino = 0;
      char perms[8], dev[16];
      if (std::sscanf(line.c_str(), "%lx-%lx %7s %lx %15s %lu", &lo, &hi, perms, &off, dev, &ino) ==
              6 &&
          ino == st.st_ino && hi - lo > (size_t(1) << 30)) {
        map_ = reinterpret_cast<void*>(lo);
        break;
      }
    }
    if (madv_ && !map_) die("lmdb: map not found in /proc/self/maps");
  }
  void close() override {
    if (rtxn_) mdb_txn_abort(rtxn_);
    rtxn_ = nullptr;
    if (env_) mdb_env_close(env_);
    env_ = nullptr;
  }
  void putBatch(const std::vector<KV>& kv) override {
    MDB_txn* t;
    check(mdb_txn_begin(env_, nullptr, 0, &t), "txn_begin");
    for (auto& e : kv) {
      MDB_val k{e.first.size(), const_cast<char*>(e.first.data())};
      MDB_val v{e.second.size(), const_cast<char*>(e.second.data())};
      check(mdb_put(t, dbi_, &k, &v, 0), "put");
    }
    check(mdb_txn_commit(t), "commit");
    touched_ = 64;  // puts fault leaf pages in through the map too: check after each commit
    maybeDrop();
  }
  void eraseBatch(const std::vector<std::string>& keys) override {
    MDB_txn* t;
    check(mdb_txn_begin(env_, nullptr, 0, &t), "txn_begin");
    for (auto& key : keys) {
      MDB_val k{key.size(), const_cast<char*>(key.data())};
      int rc = mdb_del(t, dbi_, &k, nullptr);
      if (rc != 0 && rc != MDB_NOTFOUND) check(rc, "del");
    }
    check(mdb_txn_commit(t), "commit");
  }
  bool get(const std::string& key, const Sink& sink) override {
    check(mdb_txn_renew(rtxn_), "renew");
    bool found = getIn(key, sink);
    mdb_txn_reset(rtxn_);
    maybeDrop();
    return found;
  }
  size_t getMany(const std::vector<std::string>& keys, const Sink& sink) override {
    check(mdb_txn_renew(rtxn_), "renew");
    size_t n = 0;
    for (auto& k : keys) n += getIn(k, sink);
    mdb_txn_reset(rtxn_);
    maybeDrop();
    return n;
  }
  uint64_t scan(
      const std::function<void(const char*, size_t, const uint8_t*, size_t)>& fn) override {
    check(mdb_txn_renew(rtxn_), "renew");
    MDB_cursor* c;
    check(mdb_cursor_open(rtxn_, dbi_, &c), "cursor");
    MDB_val k, v;
    uint64_t n = 0;
    int rc = mdb_cursor_get(c, &k, &v, MDB_FIRST);
    while (rc == 0) {
      fn(static_cast<const char*>(k.mv_data), k.mv_size, static_cast<const uint8_t*>(v.mv_data),
         v.mv_size);
      ++touched_;
      maybeDrop();
      ++n;
      rc = mdb_cursor_get(c, &k, &v, MDB_NEXT);
    }
    if (rc != MDB_NOTFOUND) check(rc, "cursor_get");
    mdb_cursor_close(c);
    mdb_txn_reset(rtxn_);
    return n;
  }
  // LMDB keeps no checksums: a clean open and a full ordered walk is all it can check.
  std::string check() override {
    std::string last;
    bool ordered = true;
    scan([&](const char* k, size_t n, const uint8_t*, size_t) {
      std::string key(k, n);
      if (!last.empty() && !(last < key)) ordered = false;
      last = key;
    });
    return ordered ? "" : "keys out of order";
  }

 private:
  bool getIn(const std::string& key, const Sink& sink) {
    MDB_val k{key.size(), const_cast<char*>(key.data())}, v;
    int rc = mdb_get(rtxn_, dbi_, &k, &v);
    if (rc == MDB_NOTFOUND) return false;
    check(rc, "get");
    sink(static_cast<const uint8_t*>(v.mv_data), v.mv_size);
    ++touched_;
    return true;
  }
  // Every 64 operations, reads this process's file-backed resident pages (statm's third field:
  // RssFile + RssShmem) and, above kFileBudget, drops the whole map's page-table entries.
  void maybeDrop() {
    if (!madv_ || touched_ < 64) return;
    touched_ = 0;
    long size = 0, resident = 0, shared = 0;
    if (FILE* f = std::fopen("/proc/self/statm", "r")) {
      if (std::fscanf(f, "%ld %ld %ld", &size, &resident, &shared) != 3) shared = 0;
      std::fclose(f);
    }
    const size_t page = static_cast<size_t>(::sysconf(_SC_PAGESIZE));
    if (static_cast<size_t>(shared) * page < kFileBudget) return;
    struct stat st;
    if (::fstat(fd_, &st) != 0) return;
    if (::madvise(map_, (static_cast<size_t>(st.st_size) + page - 1) / page * page,
                  MADV_DONTNEED) != 0)
      die(std::string("madvise: ") + std::strerror(errno));
    ++drops_;
  }
  static void check(int rc, const char* what) {
    if (rc != 0) die(std::string("lmdb ") + what + ": " + mdb_strerror(rc));
  }
  bool nordahead_, madv_;
  MDB_env* env_ = nullptr;
  MDB_dbi dbi_ = 0;
  MDB_txn* rtxn_ = nullptr;
  void* map_ = nullptr;
  int fd_ = -1;
  // Each page fault maps up to fault_around_bytes (64 KB) of cached file, so 64 operations add at
  // most a few MB over the budget.
  static constexpr size_t kFileBudget = size_t(32) << 20;
  size_t touched_ = 0;
  size_t drops_ = 0;
};

// RocksDB, defaults except: no block compression (values arrive compressed or not, the same bytes
// as the other stores), an explicit 8 MB LRU block cache, a 10-bit Bloom filter, WriteBatch with
// sync=true. "small" also caps the memtables (2 x 8 MB instead of 2 x 64 MB).
class RocksStore : public Store {
 public:
  explicit RocksStore(bool small) : small_(small) {}
  ~RocksStore() override { close(); }
  void open(const std::string& dir) override {
    rocksdb::Options o;
    o.create_if_missing = true;
    o.compression = rocksdb::kNoCompression;
    rocksdb::BlockBasedTableOptions t;
    t.block_cache = rocksdb::NewLRUCache(size_t(8) << 20);
    t.filter_policy.reset(rocksdb::NewBloomFilterPolicy(10));
    o.table_factory.reset(rocksdb::NewBlockBasedTableFactory(t));
    if (small_) {
      o.write_buffer_size = size_t(8) << 20;
      o.max_write_buffer_number = 2;
    }
    rocksdb::Status s = rocksdb::DB::Open(o, dir, &db_);
    if (!s.ok()) die("rocksdb open: " + s.ToString());
    sync_.sync = true;
  }
  void close() override {
    if (db_) {
      db_->Close();
      delete db_;
    }
    db_ = nullptr;
  }
  void putBatch(const std::vector<KV>& kv) override {
    rocksdb::WriteBatch b;
    for (auto& e : kv) b.Put(e.first, e.second);
    ok(db_->Write(sync_, &b), "write");
  }
  void eraseBatch(const std::vector<std::string>& keys) override {
    rocksdb::WriteBatch b;
    for (auto& k : keys) b.Delete(k);
    ok(db_->Write(sync_, &b), "delete");
  }
  bool get(const std::string& key, const Sink& sink) override {
    rocksdb::PinnableSlice v;
    rocksdb::Status s = db_->Get(rocksdb::ReadOptions(), db_->DefaultColumnFamily(), key, &v);
    if (s.IsNotFound()) return false;
    ok(s, "get");
    sink(reinterpret_cast<const uint8_t*>(v.data()), v.size());
    return true;
  }
  size_t getMany(const std::vector<std::string>& keys, const Sink& sink) override {
    const size_t n = keys.size();
    std::vector<rocksdb::Slice> ks(keys.begin(), keys.end());
    std::vector<rocksdb::PinnableSlice> vs(n);
    std::vector<rocksdb::Status> st(n);
    db_->MultiGet(rocksdb::ReadOptions(), db_->DefaultColumnFamily(), n, ks.data(), vs.data(),
                  st.data(), true);
    size_t found = 0;
    for (size_t i = 0; i < n; ++i) {
      if (st[i].IsNotFound()) continue;
      ok(st[i], "multiget");
      sink(reinterpret_cast<const uint8_t*>(vs[i].data()), vs[i].size());
      ++found;
    }
    return found;
  }
  uint64_t scan(
      const std::function<void(const char*, size_t, const uint8_t*, size_t)>& fn) override {
    std::unique_ptr<rocksdb::Iterator> it(db_->NewIterator(rocksdb::ReadOptions()));
    uint64_t n = 0;
    for (it->SeekToFirst(); it->Valid(); it->Next()) {
      fn(it->key().data(), it->key().size(), reinterpret_cast<const uint8_t*>(it->value().data()),
         it->value().size());
      ++n;
    }
    ok(it->status(), "iterate");
    return n;
  }
  std::string check() override {
    std::string out;
    rocksdb::Status s = db_->VerifyChecksum();
    if (!s.ok()) out += "VerifyChecksum: " + s.ToString() + "; ";
    scan([](const char*, size_t, const uint8_t*, size_t) {});
    return out;
  }

 private:
  static void ok(const rocksdb::Status& s, const char* what) {
    if (!s.ok()) die(std::string("rocksdb ") + what + ": " + s.ToString());
  }
  bool small_;
  rocksdb::DB* db_ = nullptr;
  rocksdb::WriteOptions sync_;
};

std::unique_ptr<Store> makeStore(const std::string& kind) {
  if (kind == "sqlite-normal") return std::make_unique<SqliteStore>(false);
  if (kind == "sqlite-full") return std::make_unique<SqliteStore>(true);
  if (kind == "sqlite-normal-16k") return std::make_unique<SqliteStore>(false, 16384);
  if (kind == "sqlite-normal-8k") return std::make_unique<SqliteStore>(false, 8192);
  if (kind == "sqlite-normal-rowid") return std::make_unique<SqliteStore>(false, 0, true);
  if (kind == "lmdb") return std::make_unique<LmdbStore>(false, false);
  if (kind == "lmdb-nordahead") return std::make_unique<LmdbStore>(true, false);
  if (kind == "lmdb-madv") return std::make_unique<LmdbStore>(false, true);
  if (kind == "lmdb-nordahead-madv") return std::make_unique<LmdbStore>(true, true);
  if (kind == "rocksdb") return std::make_unique<RocksStore>(false);
  if (kind == "rocksdb-small") return std::make_unique<RocksStore>(true);
  die("unknown store " + kind);
}

// ---------------------------------------------------------------------------------------------
// The map: a 200 x 100 x 10 block grid (x scaled to the block count), paged out in 10x10x5
// chunks of 500 blocks in random order.

constexpr int kBatch = 500;
struct Grid {
  int nx, ny = 100, nz = 10;
  int x0, y0 = -50, z0 = -5;
  explicit Grid(int blocks) : nx(blocks / 1000), x0(-(blocks / 1000) / 2) {
    if (blocks % 10000 != 0 || blocks <= 0) die("--blocks must be a positive multiple of 10000");
  }
  int count() const { return nx * ny * nz; }
  // Chunk c: 10 x 10 x 5 blocks, keys in key order.
  std::vector<std::array<int32_t, 3>> chunk(int c) const {
    const int cx = c / (10 * 2), cy = (c / 2) % 10, cz = c % 2;
    std::vector<std::array<int32_t, 3>> out;
    for (int x = 0; x < 10; ++x)
      for (int y = 0; y < 10; ++y)
        for (int z = 0; z < 5; ++z)
          out.push_back({x0 + cx * 10 + x, y0 + cy * 10 + y, z0 + cz * 5 + z});
    return out;
  }
  int chunks() const { return count() / kBatch; }
};

struct Result {
  std::vector<std::pair<std::string, std::string>> f;
  void add(const std::string& k, double v, int prec = 1) {
    char b[64];
    std::snprintf(b, sizeof b, "%.*f", prec, v);
    f.emplace_back(k, b);
  }
  void add(const std::string& k, const std::string& v) { f.emplace_back(k, v); }
  std::string line() const {
    std::string s;
    for (auto& e : f) s += e.first + "=" + e.second + " ";
    return s;
  }
};

int runOne(const std::string& kind, int zlevel, const std::string& dir, int blocks,
           const std::string& results) {
  removeTree(dir);
  makeDir(dir);
  const Grid grid(blocks);
  Codec codec;
  codec.level = zlevel;
  Result r;
  r.add("store", kind);
  r.add("zstd", std::to_string(zlevel));
  r.add("blocks", std::to_string(blocks));
  r.add("load1", loadAverage(), 2);

  const ProcStatus base = readStatus();
  resetPeakRss();
  r.add("rss_base_mb", base.rss_kb / 1024.0);

  auto store = makeStore(kind);
  store->open(dir);
  r.add("threads_open", std::to_string(readStatus().threads));

  // ---- page-out
  std::vector<int> order(static_cast<size_t>(grid.chunks()));
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::shuffle(order.begin(), order.end(), std::mt19937_64(42));
  std::vector<double> batch_ms, batch_cpu_ms;
  double raw_bytes = 0, stored_bytes = 0;
  std::vector<std::string> raw(kBatch);
  std::vector<KV> kv(kBatch + 1);
  uint64_t counter = 0;
  for (int c : order) {
    auto keys = grid.chunk(c);
    for (int i = 0; i < kBatch; ++i) raw[i] = makeBlock(keys[i][0], keys[i][1], keys[i][2], 7);
    auto t0 = Clock::now();
    const double c0 = threadCpuUs();
    for (int i = 0; i < kBatch; ++i) {
      kv[i].first = encodeKey(keys[i][0], keys[i][1], keys[i][2]);
      codec.encode(raw[i], kv[i].second);
      raw_bytes += static_cast<double>(raw[i].size());
      stored_bytes += static_cast<double>(kv[i].second.size());
    }
    kv[kBatch] = {kCounterKey, encodeCounter(++counter)};
    store->putBatch(kv);
    batch_ms.push_back(usSince(t0) / 1000.0);
    batch_cpu_ms.push_back((threadCpuUs() - c0) / 1000.0);
  }
  double write_s = 0;
  for (double v : batch_ms) write_s += v / 1000.0;
  r.add("write_blocks_s", blocks / write_s, 0);
  r.add("write_raw_mb_s", raw_bytes / 1e6 / write_s);
  r.add("ratio", raw_bytes / stored_bytes, 2);
  r.add("raw_mb", raw_bytes / 1e6);
  r.add("batch_p50_ms", percentile(batch_ms, 0.5), 2);
  r.add("batch_p99_ms", percentile(batch_ms, 0.99), 2);
  r.add("batch_max_ms", percentile(batch_ms, 1.0), 2);
  r.add("batch_cpu_p50_ms", percentile(batch_cpu_ms, 0.5), 2);
  r.add("batch_cpu_p99_ms", percentile(batch_cpu_ms, 0.99), 2);
  const ProcStatus after_write = readStatus();
  r.add("threads_write", std::to_string(after_write.threads));
  r.add("hwm_write_mb", after_write.hwm_kb / 1024.0);
  r.add("anon_write_mb", after_write.anon_kb / 1024.0);
  r.add("file_write_mb", (after_write.file_kb + after_write.shmem_kb) / 1024.0);
  r.add("rss_write_mb", after_write.rss_kb / 1024.0);
  auto tc = Clock::now();
  store->close();
  r.add("close_ms", usSince(tc) / 1000.0);
  r.add("disk_mb", static_cast<double>(diskBytes(dir)) / 1e6);

  // ---- reopen, cold reads
  evictFromPageCache(dir);
  auto to = Clock::now();
  store->open(dir);
  r.add("reopen_ms", usSince(to) / 1000.0, 2);
  std::mt19937_64 rng(1234);
  std::uniform_int_distribution<int> ux(0, grid.nx - 1), uy(0, grid.ny - 1), uz(0, grid.nz - 1);
  std::uniform_int_distribution<int> cx(0, grid.nx - 4), cy(0, grid.ny - 4), cz(0, grid.nz - 4);
  std::string block;
  size_t bad = 0;
  auto decodeInto = [&](const uint8_t* p, size_t n) {
    if (!codec.decode(p, n, block)) ++bad;
  };
  auto singleReads = [&](int n) {
    std::vector<double> us;
    for (int i = 0; i < n; ++i) {
      const std::string k = encodeKey(grid.x0 + ux(rng), grid.y0 + uy(rng), grid.z0 + uz(rng));
      auto t0 = Clock::now();
      if (!store->get(k, decodeInto)) ++bad;
      us.push_back(usSince(t0));
    }
    return us;
  };
  std::vector<double> cube_cpu_us;
  auto cubeReads = [&](int n) {
    std::vector<double> us;
    cube_cpu_us.clear();
    std::vector<std::string> keys;
    for (int i = 0; i < n; ++i) {
      const int x = grid.x0 + cx(rng), y = grid.y0 + cy(rng), z = grid.z0 + cz(rng);
      keys.clear();
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b)
          for (int c = 0; c < 4; ++c) keys.push_back(encodeKey(x + a, y + b, z + c));
      auto t0 = Clock::now();
      const double c0 = threadCpuUs();
      if (store->getMany(keys, decodeInto) != keys.size()) ++bad;
      us.push_back(usSince(t0));
      cube_cpu_us.push_back(threadCpuUs() - c0);
    }
    return us;
  };
  auto cold1 = singleReads(2000);
  auto cold64 = cubeReads(200);
  r.add("cold_get_p50_us", percentile(cold1, 0.5));
  r.add("cold_get_p99_us", percentile(cold1, 0.99));
  r.add("cold_cube_p50_us", percentile(cold64, 0.5));
  r.add("cold_cube_p99_us", percentile(cold64, 0.99));

  // ---- full ordered scan (reads and decodes every value; warms the page cache)
  auto ts = Clock::now();
  uint64_t n_blocks = 0;
  std::string prev;
  bool ordered = true;
  store->scan([&](const char* k, size_t kn, const uint8_t* v, size_t vn) {
    if (kn != 12) return;
    std::string key(k, kn);
    if (!prev.empty() && !(prev < key)) ordered = false;
    prev.swap(key);
    decodeInto(v, vn);
    ++n_blocks;
  });
  r.add("scan_s", secondsSince(ts), 2);
  if (n_blocks != static_cast<uint64_t>(blocks) || !ordered) die("scan found wrong blocks");

  // ---- warm reads
  auto warm1 = singleReads(20000);
  auto warm64 = cubeReads(1000);
  r.add("get_p50_us", percentile(warm1, 0.5));
  r.add("get_p99_us", percentile(warm1, 0.99));
  r.add("cube_p50_us", percentile(warm64, 0.5));
  r.add("cube_p99_us", percentile(warm64, 0.99));
  r.add("cube_cpu_p50_us", percentile(cube_cpu_us, 0.5));
  r.add("cube_cpu_p99_us", percentile(cube_cpu_us, 0.99));

  // ---- read every block once, random order, and check it
  std::vector<std::array<int32_t, 3>> all;
  for (int c = 0; c < grid.chunks(); ++c)
    for (auto& k : grid.chunk(c)) all.push_back(k);
  std::shuffle(all.begin(), all.end(), std::mt19937_64(99));
  struct rusage ru0, ru1;
  ::getrusage(RUSAGE_SELF, &ru0);
  auto ta = Clock::now();
  for (auto& k : all)
    if (!store->get(encodeKey(k[0], k[1], k[2]), decodeInto)) ++bad;
  r.add("readall_s", secondsSince(ta), 2);
  ::getrusage(RUSAGE_SELF, &ru1);
  r.add("readall_minflt_per_get",
        static_cast<double>(ru1.ru_minflt - ru0.ru_minflt) / static_cast<double>(all.size()), 2);
  r.add("readall_majflt_per_get",
        static_cast<double>(ru1.ru_majflt - ru0.ru_majflt) / static_cast<double>(all.size()), 2);
  for (size_t i = 0; i < all.size(); i += 997) {  // spot-check contents
    auto& k = all[i];
    store->get(encodeKey(k[0], k[1], k[2]), decodeInto);
    if (block != makeBlock(k[0], k[1], k[2], 7)) ++bad;
  }
  const ProcStatus after_read = readStatus();
  r.add("hwm_read_mb", after_read.hwm_kb / 1024.0);
  r.add("anon_read_mb", after_read.anon_kb / 1024.0);
  r.add("file_read_mb", (after_read.file_kb + after_read.shmem_kb) / 1024.0);
  r.add("rss_read_mb", after_read.rss_kb / 1024.0);
  r.add("threads_read", std::to_string(after_read.threads));

  // ---- erase 20 batches of 500
  std::vector<double> erase_ms;
  for (int i = 0; i < 20 && i < grid.chunks(); ++i) {
    std::vector<std::string> keys;
    for (auto& k : grid.chunk(order[static_cast<size_t>(i)]))
      keys.push_back(encodeKey(k[0], k[1], k[2]));
    auto t0 = Clock::now();
    store->eraseBatch(keys);
    erase_ms.push_back(usSince(t0) / 1000.0);
  }
  r.add("erase_p50_ms", percentile(erase_ms, 0.5), 2);
  r.add("erase_p99_ms", percentile(erase_ms, 0.99), 2);
  store->close();
  r.add("disk_after_erase_mb", static_cast<double>(diskBytes(dir)) / 1e6);
  r.add("bad", std::to_string(bad));

  std::ofstream(results, std::ios::app) << r.line() << "\n";
  std::printf("%s\n", r.line().c_str());
  removeTree(dir);
  return bad == 0 ? 0 : 1;
}

// ---------------------------------------------------------------------------------------------
// Crash safety: a child (fresh exec) appends batches of 500 blocks, each with the batch counter in
// the same transaction, and reports each returned commit on a pipe; it is SIGKILLed at a random
// instant. The parent reopens, runs the store's integrity check, and verifies that every batch
// up to the stored counter is present and byte-equal, that no block of a later batch exists, and
// that the counter is at least the last commit the child saw return.

std::array<int32_t, 3> crashKey(uint64_t batch, int i) {
  const uint64_t idx = (batch - 1) * kBatch + static_cast<uint64_t>(i);
  return {static_cast<int32_t>(idx / 1000) - 500, static_cast<int32_t>((idx / 10) % 100) - 50,
          static_cast<int32_t>(idx % 10) - 5};
}

int crashChild(const std::string& kind, int zlevel, const std::string& dir, int fd) {
  Codec codec;
  codec.level = zlevel;
  auto store = makeStore(kind);
  store->open(dir);
  uint32_t b = static_cast<uint32_t>(store->counter());
  std::vector<KV> kv(kBatch + 1);
  for (;;) {
    ++b;
    for (int i = 0; i < kBatch; ++i) {
      auto k = crashKey(b, i);
      kv[i].first = encodeKey(k[0], k[1], k[2]);
      codec.encode(makeBlock(k[0], k[1], k[2], b), kv[i].second);
    }
    kv[kBatch] = {kCounterKey, encodeCounter(b)};
    store->putBatch(kv);
    if (::write(fd, &b, sizeof b) != sizeof b) return 1;
  }
}

int runCrash(const std::string& kind, int zlevel, const std::string& dir, int runs,
             const std::string& results) {
  removeTree(dir);
  makeDir(dir);
  Codec codec;
  codec.level = zlevel;
  std::mt19937_64 rng(std::hash<std::string>()(kind) ^ static_cast<uint64_t>(::getpid()));
  std::uniform_int_distribution<int> delay_ms(30, 700);
  int failures = 0, lost_acked = 0, integrity_bad = 0, partial = 0, content_bad = 0;
  uint64_t counter = 0;
  double max_recover_ms = 0;
  std::string first_error;
  for (int run = 0; run < runs; ++run) {
    int p[2];
    if (::pipe(p) != 0) die("pipe");
    pid_t pid = ::fork();
    if (pid == 0) {
      ::close(p[0]);
      std::string fd = std::to_string(p[1]), z = std::to_string(zlevel);
      ::execl("/proc/self/exe", "store_compare", "--crash-child", kind.c_str(), z.c_str(),
              dir.c_str(), fd.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
    ::close(p[1]);
    std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms(rng)));
    ::kill(pid, SIGKILL);
    int status = 0;
    ::waitpid(pid, &status, 0);
    uint32_t acked = 0, v;
    while (::read(p[0], &v, sizeof v) == sizeof v) acked = v;
    ::close(p[0]);

    auto t0 = Clock::now();
    auto store = makeStore(kind);
    store->open(dir);
    const std::string integrity = store->check();
    max_recover_ms = std::max(max_recover_ms, usSince(t0) / 1000.0);
    const uint64_t c = store->counter();
    bool ok = true;
    auto fail = [&](const std::string& why) {
      ok = false;
      if (first_error.empty()) first_error = "run " + std::to_string(run) + ": " + why;
    };
    if (!integrity.empty()) {
      ++integrity_bad;
      fail("integrity: " + integrity);
    }
    if (c < acked) {
      ++lost_acked;
      fail("counter " + std::to_string(c) + " < acknowledged " + std::to_string(acked));
    }
    std::string block;
    for (uint64_t b = 1; b <= c; ++b)
      for (int i = 0; i < kBatch; ++i) {
        auto k = crashKey(b, i);
        bool got = store->get(encodeKey(k[0], k[1], k[2]), [&](const uint8_t* q, size_t n) {
          if (!codec.decode(q, n, block)) block.clear();
        });
        if (!got || block != makeBlock(k[0], k[1], k[2], b)) {
          ++content_bad;
          fail("batch " + std::to_string(b) + " block " + std::to_string(i) + " missing/differs");
          b = c;
          break;
        }
      }
    uint64_t n12 = 0;
    store->scan([&](const char*, size_t kn, const uint8_t*, size_t) { n12 += kn == 12; });
    if (n12 != c * kBatch) {
      ++partial;
      fail(std::to_string(n12) + " blocks stored for counter " + std::to_string(c));
    }
    store->close();
    if (!ok) ++failures;
    counter = c;
  }
  Result r;
  r.add("crash_store", kind);
  r.add("zstd", std::to_string(zlevel));
  r.add("runs", std::to_string(runs));
  r.add("failed_runs", std::to_string(failures));
  r.add("integrity_bad", std::to_string(integrity_bad));
  r.add("lost_acked", std::to_string(lost_acked));
  r.add("partial_batches", std::to_string(partial));
  r.add("content_bad", std::to_string(content_bad));
  r.add("batches_committed", std::to_string(counter));
  r.add("max_recover_ms", max_recover_ms);
  if (!first_error.empty()) r.add("first_error", "\"" + first_error + "\"");
  std::ofstream(results, std::ios::app) << r.line() << "\n";
  std::printf("%s\n", r.line().c_str());
  removeTree(dir);
  return failures == 0 ? 0 : 1;
}

// ---------------------------------------------------------------------------------------------
// Driver

int spawnSelf(const std::vector<std::string>& args) {
  pid_t pid = ::fork();
  if (pid == 0) {
    std::vector<char*> av;
    av.push_back(const_cast<char*>("store_compare"));
    for (auto& a : args) av.push_back(const_cast<char*>(a.c_str()));
    av.push_back(nullptr);
    ::execv("/proc/self/exe", av.data());
    ::_exit(127);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::vector<std::map<std::string, std::string>> readResults(const std::string& path) {
  std::vector<std::map<std::string, std::string>> out;
  std::ifstream f(path);
  std::string line;
  while (std::getline(f, line)) {
    std::map<std::string, std::string> m;
    std::istringstream is(line);
    std::string tok;
    while (is >> tok) {
      auto eq = tok.find('=');
      if (eq != std::string::npos) m[tok.substr(0, eq)] = tok.substr(eq + 1);
    }
    out.push_back(m);
  }
  return out;
}

void printTables(const std::string& path) {
  auto rows = readResults(path);
  auto col = [](std::map<std::string, std::string>& m, const char* k) {
    return m.count(k) ? m[k] : std::string("-");
  };
  std::printf(
      "\n| store | zstd | ratio | blocks/s | raw MB/s | batch p50 ms | batch p99 ms | "
      "get p50/p99 us | cube64 p50/p99 us | cold get p50/p99 us | cold cube64 p50/p99 "
      "us | scan s | erase500 p50/p99 ms | disk MB | reopen ms |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (auto& m : rows) {
    if (!m.count("store")) continue;
    std::printf(
        "| %s | %s | %s | %s | %s | %s | %s | %s / %s | %s / %s | %s / %s | %s / %s | %s "
        "| %s / %s | %s | %s |\n",
        col(m, "store").c_str(), col(m, "zstd").c_str(), col(m, "ratio").c_str(),
        col(m, "write_blocks_s").c_str(), col(m, "write_raw_mb_s").c_str(),
        col(m, "batch_p50_ms").c_str(), col(m, "batch_p99_ms").c_str(),
        col(m, "get_p50_us").c_str(), col(m, "get_p99_us").c_str(), col(m, "cube_p50_us").c_str(),
        col(m, "cube_p99_us").c_str(), col(m, "cold_get_p50_us").c_str(),
        col(m, "cold_get_p99_us").c_str(), col(m, "cold_cube_p50_us").c_str(),
        col(m, "cold_cube_p99_us").c_str(), col(m, "scan_s").c_str(),
        col(m, "erase_p50_ms").c_str(), col(m, "erase_p99_ms").c_str(), col(m, "disk_mb").c_str(),
        col(m, "reopen_ms").c_str());
  }
  std::printf(
      "\n| store | zstd | load1 | batch CPU p50/p99 ms | cube64 CPU p50/p99 us | read-all s "
      "| minor faults per get (read-all) |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  for (auto& m : rows) {
    if (!m.count("store")) continue;
    std::printf("| %s | %s | %s | %s / %s | %s / %s | %s | %s |\n", col(m, "store").c_str(),
                col(m, "zstd").c_str(), col(m, "load1").c_str(), col(m, "batch_cpu_p50_ms").c_str(),
                col(m, "batch_cpu_p99_ms").c_str(), col(m, "cube_cpu_p50_us").c_str(),
                col(m, "cube_cpu_p99_us").c_str(), col(m, "readall_s").c_str(),
                col(m, "readall_minflt_per_get").c_str());
  }
  std::printf(
      "\n| store | zstd | RSS base MB | HWM after write MB | RSS = anon + file after "
      "write MB | HWM after read-all MB | RSS = anon + file after read-all MB | threads "
      "open/write/read |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (auto& m : rows) {
    if (!m.count("store")) continue;
    std::printf("| %s | %s | %s | %s | %s = %s + %s | %s | %s = %s + %s | %s / %s / %s |\n",
                col(m, "store").c_str(), col(m, "zstd").c_str(), col(m, "rss_base_mb").c_str(),
                col(m, "hwm_write_mb").c_str(), col(m, "rss_write_mb").c_str(),
                col(m, "anon_write_mb").c_str(), col(m, "file_write_mb").c_str(),
                col(m, "hwm_read_mb").c_str(), col(m, "rss_read_mb").c_str(),
                col(m, "anon_read_mb").c_str(), col(m, "file_read_mb").c_str(),
                col(m, "threads_open").c_str(), col(m, "threads_write").c_str(),
                col(m, "threads_read").c_str());
  }
  std::printf(
      "\n| store | zstd | kills | failed runs | integrity bad | acked lost | partial batch "
      "| content bad | batches committed | max reopen+check ms |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  for (auto& m : rows) {
    if (!m.count("crash_store")) continue;
    std::printf("| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n",
                col(m, "crash_store").c_str(), col(m, "zstd").c_str(), col(m, "runs").c_str(),
                col(m, "failed_runs").c_str(), col(m, "integrity_bad").c_str(),
                col(m, "lost_acked").c_str(), col(m, "partial_batches").c_str(),
                col(m, "content_bad").c_str(), col(m, "batches_committed").c_str(),
                col(m, "max_recover_ms").c_str());
    if (m.count("first_error")) std::printf("  first error: %s\n", m["first_error"].c_str());
  }
}

/// The command line: the comparison, or one of the runs it execs itself for (spawnSelf()).
struct Arguments {
  int blocks = 200000, crash_runs = 20;
  bool crash = true;
  // store:zstd-level pairs; the default is every store at levels 0, 1 and 3 plus the RSS
  // variants of LMDB and RocksDB at level 1.
  std::vector<std::string> configs = {
      "sqlite-normal:0", "sqlite-normal:1", "sqlite-normal:3",  "sqlite-full:0", "sqlite-full:1",
      "sqlite-full:3",   "lmdb:0",          "lmdb:1",           "lmdb:3",        "rocksdb:0",
      "rocksdb:1",       "rocksdb:3",       "lmdb-nordahead:1", "lmdb-madv:1",   "rocksdb-small:1"};
  // Also available: lmdb-nordahead-madv (both), and SQLite schema variants sqlite-normal-8k,
  // sqlite-normal-16k (page_size) and sqlite-normal-rowid (a rowid table with the key as a
  // separately indexed BLOB PRIMARY KEY, so values up to ~4 KB stay in the table's leaf pages).
  std::vector<std::string> crash_configs = {"sqlite-normal:1", "sqlite-full:1", "lmdb:1",
                                            "rocksdb:1"};
  std::string dir;
  // The runs' own arguments: store, zstd level, folder, blocks or runs (or the pipe's fd), results.
  std::tuple<std::string, int, std::string, int, std::string> one, crash_run;
  std::tuple<std::string, int, std::string, int> crash_child;
};

void addArguments(CLI::App* app, Arguments* a) {
  app->description(
      "LMDB vs RocksDB vs SQLite for paging TSDF map blocks (tools/bench/store_compare.md).\n"
      "Every configuration runs in a fresh process; results go to DIR/results.txt and, as\n"
      "markdown tables, to stdout.");
  app->add_option("dir", a->dir, "where the stores and results.txt are written (required)");
  app->add_option("--blocks", a->blocks,
                  "map blocks, a positive multiple of 10000 (default 200000)");
  app->add_option("--crash-runs", a->crash_runs, "kills per store in the crash test (default 20)")
      ->check(stereo_fusion::cli::positiveNumber());
  app->add_option("--configs", a->configs, "store:zstd-level pairs to measure (default: all)")
      ->delimiter(',')
      ->type_name("s:z,...");
  app->add_option("--crash-configs", a->crash_configs,
                  "store:zstd-level pairs to crash-test (default: one of each store at level 1)")
      ->delimiter(',')
      ->type_name("s:z,...");
  app->add_flag_callback(
      "--no-crash", [a] { a->crash = false; }, "skip the crash test");
  // The runs the comparison execs (hidden): each stands for the whole comparison.
  CLI::Option* one = app->add_option("--one", a->one)->group("");
  CLI::Option* crash = app->add_option("--crash", a->crash_run)->group("")->excludes(one);
  CLI::Option* child =
      app->add_option("--crash-child", a->crash_child)->group("")->excludes(one)->excludes(crash);
  app->callback([a, one, crash, child] {
    if (one->count() + crash->count() + child->count() == 0 && a->dir.empty())
      throw CLI::RequiredError("dir");
  });
}

}  // namespace

int main(int argc, char** argv) {
  Arguments a;
  CLI::App app("", "store_compare");
  addArguments(&app, &a);
  if (const auto exit_code = stereo_fusion::cli::parseOrExitCode(app, argc, argv))
    return *exit_code;
  if (app.count("--crash-child")) return std::apply(crashChild, a.crash_child);
  if (app.count("--one")) return std::apply(runOne, a.one);
  if (app.count("--crash")) return std::apply(runCrash, a.crash_run);
  const int blocks = a.blocks, crash_runs = a.crash_runs;
  const std::string& dir = a.dir;
  Grid check_grid(blocks);
  makeDir(dir);
  const std::string results = dir + "/results.txt";
  std::remove(results.c_str());
  int rc = 0;
  auto t0 = Clock::now();
  for (const std::string& c : a.configs) {
    auto colon = c.find(':');
    const std::string kind = c.substr(0, colon);
    const std::string z = colon == std::string::npos ? "0" : c.substr(colon + 1);
    auto tc = Clock::now();
    rc |= spawnSelf(
        {"--one", kind, z, dir + "/db-" + kind + "-z" + z, std::to_string(blocks), results});
    std::fprintf(stderr, "[%6.1f s] %s zstd %s done in %.1f s\n", secondsSince(t0), kind.c_str(),
                 z.c_str(), secondsSince(tc));
  }
  if (a.crash)
    for (const std::string& c : a.crash_configs) {
      auto colon = c.find(':');
      const std::string kind = c.substr(0, colon);
      const std::string z = colon == std::string::npos ? "0" : c.substr(colon + 1);
      auto tc = Clock::now();
      rc |= spawnSelf(
          {"--crash", kind, z, dir + "/crash-" + kind, std::to_string(crash_runs), results});
      std::fprintf(stderr, "[%6.1f s] crash %s done in %.1f s\n", secondsSince(t0), kind.c_str(),
                   secondsSince(tc));
    }
  printTables(results);
  std::printf("\ntotal %.0f s\n", secondsSince(t0));
  return rc;
}
