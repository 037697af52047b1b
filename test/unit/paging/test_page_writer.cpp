// The page writer: a page is readable from the hand-over until the store holds it, batches
// reach the store in order, and a refused write keeps every later page readable for the host.
#include <gtest/gtest.h>

#include <random>
#include <sys/resource.h>

#include <csignal>
#include <filesystem>

#include "stereo_fusion/paging/PageWriter.h"

using namespace stereo_fusion;
namespace fs = std::filesystem;

namespace {
const BlockStoreIdentity kIdentity{0.02, 4.0};

PageWriter::Page page(size_t bytes, uint8_t value) {
  return std::make_shared<const std::vector<uint8_t>>(bytes, value);
}

/// A page the store cannot compress (its pages are zstd frames): random bytes.
PageWriter::Page noisePage(size_t bytes, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<uint8_t> noise(bytes);
  for (uint8_t& b : noise) b = static_cast<uint8_t>(rng());
  return std::make_shared<const std::vector<uint8_t>>(std::move(noise));
}

struct Store {
  fs::path dir;
  std::unique_ptr<BlockStore> reader;
  std::unique_ptr<PageWriter> writer;
  Store() {
    dir = fs::temp_directory_path() /
          ("sf_writer_" + std::to_string(::getpid()) + "_" +
           ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir);
    std::string error;
    reader = BlockStore::open((dir / "map.sqlite").string(), kIdentity, &error);
    EXPECT_TRUE(reader) << error;
    writer = std::make_unique<PageWriter>(
        BlockStore::open((dir / "map.sqlite").string(), kIdentity, &error));
  }
  ~Store() {
    writer.reset();
    reader.reset();
    fs::remove_all(dir);
  }
};
}  // namespace

TEST(PageWriter, APageIsReadableFromTheHandOverUntilTheStoreHoldsIt) {
  Store s;
  // Many batches, the same keys again and again: whenever read, a key shows its newest page,
  // from the writer while pending, from the store once written.
  for (uint8_t round = 1; round <= 20; ++round) {
    std::vector<BlockKey> keys;
    std::vector<PageWriter::Page> pages;
    for (int k = 0; k < 50; ++k) {
      keys.push_back({k, 0, 0});
      pages.push_back(page(3000, round));
    }
    s.writer->write(keys, pages);
    for (int k = 0; k < 50; k += 7) {
      std::vector<uint8_t> bytes;
      s.writer->releaseWritten();  // as the host does before it reads the store
      if (PageWriter::Page pending = s.writer->find({k, 0, 0})) {
        bytes = *pending;
      } else {
        std::string error;
        ASSERT_TRUE(s.reader->read({k, 0, 0}, &bytes, &error)) << error;
      }
      ASSERT_EQ(bytes.size(), 3000u);
      EXPECT_EQ(bytes[0], round) << "key " << k << " shows an older page";
    }
  }
  // The loop's last release may already have let round 20 go; a page handed over after it is
  // held until released, however soon the thread writes it.
  s.writer->write({{3, 0, 0}}, {page(3000, 21)});
  s.writer->flush();
  const PageWriter::Page kept = s.writer->find({3, 0, 0});
  ASSERT_NE(kept, nullptr) << "written, kept until released";
  EXPECT_EQ(kept->at(0), 21);
  s.writer->releaseWritten();
  EXPECT_EQ(s.writer->pendingBytes(), 0u);
  EXPECT_EQ(s.writer->find({3, 0, 0}), nullptr);
  std::vector<uint8_t> bytes;
  std::string error;
  ASSERT_TRUE(s.reader->read({49, 0, 0}, &bytes, &error)) << error;
  EXPECT_EQ(bytes, std::vector<uint8_t>(3000, 20));
  std::vector<BlockKey> keys;
  EXPECT_FALSE(s.writer->failedKeys(&keys, &error));
}

TEST(PageWriter, ARefusedWriteKeepsItsPagesAndEveryLaterOneForTheHost) {
  Store s;
  s.writer->write({{1, 0, 0}}, {page(100, 1)});
  s.writer->flush();
  s.writer->releaseWritten();
  struct rlimit old_limit {};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old_limit), 0);
  const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);
  struct rlimit small = old_limit;
  small.rlim_cur = 256 * 1024;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  std::vector<BlockKey> big_keys;
  std::vector<PageWriter::Page> big_pages;
  for (int k = 0; k < 100; ++k) {
    big_keys.push_back({k, 1, 0});
    big_pages.push_back(noisePage(8000, k));
  }
  s.writer->write(big_keys, big_pages);  // 800 KB: beyond the limit
  s.writer->write({{0, 2, 0}}, {page(10, 3)});
  s.writer->flush();
  setrlimit(RLIMIT_FSIZE, &old_limit);
  std::signal(SIGXFSZ, old_handler);
  std::vector<BlockKey> failed;
  std::string error;
  ASSERT_TRUE(s.writer->failedKeys(&failed, &error));
  EXPECT_FALSE(error.empty());
  EXPECT_EQ(failed.size(), 101u) << "the refused batch and the one after it";
  ASSERT_NE(s.writer->find({5, 1, 0}), nullptr);
  EXPECT_EQ(s.writer->find({5, 1, 0})->size(), 8000u);
  ASSERT_NE(s.writer->find({0, 2, 0}), nullptr);
  EXPECT_EQ(s.writer->find({1, 0, 0}), nullptr) << "written before the failure";
  s.writer->forgetFailed();
  EXPECT_FALSE(s.writer->failedKeys(&failed, &error));
  EXPECT_EQ(s.writer->pendingBytes(), 0u);
  // Room again: writes go on.
  s.writer->write({{7, 7, 7}}, {page(10, 4)});
  s.writer->flush();
  std::vector<uint8_t> bytes;
  ASSERT_TRUE(s.reader->read({7, 7, 7}, &bytes, &error)) << error;
}
