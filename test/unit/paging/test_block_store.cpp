// The block store: pages written, read, erased and listed; a foreign or mismatched file refused
// with a sentence; a private store gone with its map.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <sqlite3.h>

#include "stereo_fusion/paging/BlockStore.h"

using namespace stereo_fusion;
namespace fs = std::filesystem;

namespace {
struct TempFolder {
  fs::path path;
  TempFolder() {
    path = fs::temp_directory_path() /
           ("sf_store_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempFolder() { fs::remove_all(path); }
};
const BlockStoreIdentity kIdentity{0.02, 4.0};
}  // namespace

TEST(BlockStore, WritesReadsErasesAndListsPagesAcrossAReopen) {
  TempFolder dir;
  const std::string file = (dir.path / "map.sqlite").string();
  std::string error;
  {
    auto store = BlockStore::open(file, kIdentity, &error);
    ASSERT_TRUE(store) << error;
    const std::vector<BlockKey> keys = {{1, 2, 3}, {-5, 0, 7}, {0, 0, -1}};
    const std::vector<std::vector<uint8_t>> pages = {{1, 2, 3}, {}, std::vector<uint8_t>(9000, 7)};
    ASSERT_TRUE(store->write(keys, pages, &error)) << error;
    std::vector<uint8_t> page;
    ASSERT_TRUE(store->read({-5, 0, 7}, &page, &error));
    EXPECT_TRUE(page.empty());
    ASSERT_TRUE(store->read({0, 0, -1}, &page, &error));
    EXPECT_EQ(page, pages[2]);
    EXPECT_FALSE(store->read({9, 9, 9}, &page, &error));
    EXPECT_TRUE(error.empty()) << "a missing page is no error: " << error;
    // A second write of a key replaces its page.
    ASSERT_TRUE(store->write({{1, 2, 3}}, std::vector<std::vector<uint8_t>>{{9}}, &error)) << error;
    ASSERT_TRUE(store->read({1, 2, 3}, &page, &error));
    EXPECT_EQ(page, std::vector<uint8_t>{9});
    ASSERT_TRUE(store->erase({{-5, 0, 7}, {4, 4, 4}}, &error)) << error;
  }
  auto reopened = BlockStore::open(file, kIdentity, &error);
  ASSERT_TRUE(reopened) << error;
  std::vector<BlockKey> listed;
  ASSERT_TRUE(reopened->keys(&listed, &error)) << error;
  // Sorted as BlockKey sorts (z, then y, then x).
  EXPECT_EQ(listed, (std::vector<BlockKey>{{0, 0, -1}, {1, 2, 3}}));
  ASSERT_TRUE(reopened->clear(&error)) << error;
  ASSERT_TRUE(reopened->keys(&listed, &error));
  EXPECT_TRUE(listed.empty());
}

TEST(BlockStore, RefusesAForeignFileAndAnotherVoxelGrid) {
  TempFolder dir;
  const std::string text = (dir.path / "notes.sqlite").string();
  std::ofstream(text) << "these are not pages, but they are longer than a header would be. "
                         "SQLite reads the first hundred bytes as its header and refuses them."
                      << std::string(200, 'x');
  std::string error;
  EXPECT_FALSE(BlockStore::open(text, kIdentity, &error));
  EXPECT_NE(error.find("not a stereo_fusion block store"), std::string::npos) << error;

  const std::string file = (dir.path / "map.sqlite").string();
  ASSERT_TRUE(BlockStore::open(file, kIdentity, &error)) << error;
  error.clear();
  EXPECT_FALSE(BlockStore::open(file, BlockStoreIdentity{0.05, 4.0}, &error));
  EXPECT_NE(error.find("voxel_size_m"), std::string::npos) << error;
  // A folder where a file should be made cannot hold a store either.
  error.clear();
  EXPECT_FALSE(
      BlockStore::open((dir.path / "map.sqlite" / "inner.sqlite").string(), kIdentity, &error));
  EXPECT_FALSE(error.empty());
}

TEST(BlockStore, APrivateStoreIsRemovedWithItsMap) {
  TempFolder dir;
  std::string error;
  std::string file;
  {
    auto a = BlockStore::openPrivate(dir.path.string(), kIdentity, &error);
    auto b = BlockStore::openPrivate(dir.path.string(), kIdentity, &error);
    ASSERT_TRUE(a && b) << error;
    EXPECT_NE(a->file(), b->file()) << "each map its own store";
    ASSERT_TRUE(a->write({{1, 1, 1}}, std::vector<std::vector<uint8_t>>{{1}}, &error)) << error;
    file = a->file();
    EXPECT_TRUE(fs::exists(file));
  }
  EXPECT_FALSE(fs::exists(file));
  EXPECT_FALSE(fs::exists(file + "-wal"));
  EXPECT_TRUE(fs::is_empty(dir.path));
}

TEST(BlockStore, ACommitWritesErasesAndRecordsItsStateInOneTransaction) {
  TempFolder dir;
  const std::string file = (dir.path / "map.sqlite").string();
  std::string error;
  auto page = [](std::initializer_list<uint8_t> bytes) {
    return std::make_shared<const std::vector<uint8_t>>(bytes);
  };
  {
    auto store = BlockStore::open(file, kIdentity, &error, /*durable=*/true);
    ASSERT_TRUE(store) << error;
    std::vector<uint8_t> state;
    EXPECT_FALSE(store->readState(&state, &error));
    EXPECT_TRUE(error.empty()) << "no checkpoint yet is no error: " << error;
    StoreCommit first;
    first.keys = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
    first.pages = {page({1}), page({2}), page({3})};
    first.state = {10, 11};
    ASSERT_TRUE(store->commit(first, &error)) << error;
    StoreCommit second;
    second.erase = {{1, 0, 0}, {7, 7, 7}};  // a missing key is no error
    second.keys = {{2, 0, 0}, {3, 0, 0}};
    second.pages = {page({30}), page({4})};
    second.state = {20};
    ASSERT_TRUE(store->commit(second, &error)) << error;
  }
  auto store = BlockStore::open(file, kIdentity, &error, true);
  ASSERT_TRUE(store) << error;
  std::vector<uint8_t> state;
  ASSERT_TRUE(store->readState(&state, &error)) << error;
  EXPECT_EQ(state, std::vector<uint8_t>{20});
  std::vector<std::pair<BlockKey, std::vector<uint8_t>>> pages;
  ASSERT_TRUE(store->eachPage(
      [&](const BlockKey& key, const uint8_t* data, size_t size) {
        pages.emplace_back(key, std::vector<uint8_t>(data, data + size));
        return true;
      },
      &error))
      << error;
  const std::vector<std::pair<BlockKey, std::vector<uint8_t>>> expected = {
      {{0, 0, 0}, {1}}, {{2, 0, 0}, {30}}, {{3, 0, 0}, {4}}};
  EXPECT_EQ(pages, expected);
  // clear_first: the commit's pages are all the store holds after it.
  StoreCommit whole;
  whole.clear_first = true;
  whole.keys = {{5, 5, 5}};
  whole.pages = {page({5})};
  ASSERT_TRUE(store->commit(whole, &error)) << error;
  std::vector<BlockKey> keys;
  ASSERT_TRUE(store->keys(&keys, &error)) << error;
  EXPECT_EQ(keys, (std::vector<BlockKey>{{5, 5, 5}}));
  // A visitor that stops the walk.
  size_t visited = 0;
  EXPECT_FALSE(store->eachPage(
      [&](const BlockKey&, const uint8_t*, size_t) { return ++visited < 1; }, &error));
  EXPECT_EQ(visited, 1u);
  EXPECT_TRUE(error.empty());
}

TEST(BlockStore, PagesAreStoredCompressedAndACorruptedOneIsAnError) {
  TempFolder dir;
  const std::string file = (dir.path / "map.sqlite").string();
  std::string error;
  const std::vector<uint8_t> page(64 * 1024, 7);
  {
    auto store = BlockStore::open(file, kIdentity, &error);
    ASSERT_TRUE(store) << error;
    ASSERT_TRUE(store->write({{1, 1, 1}, {2, 2, 2}}, {page, page}, &error)) << error;
  }
  // The blob on disk is a zstd frame far smaller than the page; one is then garbled.
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(file.c_str(), &db), SQLITE_OK);
  sqlite3_stmt* length = nullptr;
  ASSERT_EQ(
      sqlite3_prepare_v2(db, "SELECT length(page) FROM pages WHERE x = 1", -1, &length, nullptr),
      SQLITE_OK);
  ASSERT_EQ(sqlite3_step(length), SQLITE_ROW);
  EXPECT_LT(sqlite3_column_int(length, 0), 1024);
  sqlite3_finalize(length);
  ASSERT_EQ(sqlite3_exec(db, "UPDATE pages SET page = x'0102030405060708' WHERE x = 2", nullptr,
                         nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(db);
  auto store = BlockStore::open(file, kIdentity, &error);
  ASSERT_TRUE(store) << error;
  std::vector<uint8_t> back;
  ASSERT_TRUE(store->read({1, 1, 1}, &back, &error)) << error;
  EXPECT_EQ(back, page);
  EXPECT_FALSE(store->read({2, 2, 2}, &back, &error));
  EXPECT_NE(error.find("corrupted store"), std::string::npos) << error;
}
