#include "stereo_fusion/paging/PageWriter.h"

namespace stereo_fusion {

PageWriter::PageWriter(std::unique_ptr<BlockStore> store)
    : store_(std::move(store)), thread_([this] { run(); }) {}

PageWriter::~PageWriter() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  work_.notify_one();
  thread_.join();
}

uint64_t PageWriter::queueLocked(Batch batch) {
  batch.id = next_batch_++;
  const std::vector<BlockKey>& keys = batch.commit ? batch.commit->keys : batch.keys;
  const std::vector<Page>& pages = batch.commit ? batch.commit->pages : batch.pages;
  for (size_t i = 0; i < keys.size(); ++i) {
    Pending& entry = pending_[keys[i]];
    if (entry.page) pending_bytes_ -= entry.page->size();  // an older page of the key
    entry = Pending{batch.id, pages[i]};
    pending_bytes_ += pages[i]->size();
  }
  const uint64_t id = batch.id;
  batches_.push_back(std::move(batch));
  return id;
}

void PageWriter::write(std::vector<BlockKey> keys, std::vector<Page> pages) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    queueLocked(Batch{0, std::move(keys), std::move(pages), nullptr});
  }
  work_.notify_one();
}

uint64_t PageWriter::commit(StoreCommit commit) {
  uint64_t id = 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    id = queueLocked(Batch{0, {}, {}, std::make_unique<StoreCommit>(std::move(commit))});
  }
  work_.notify_one();
  return id;
}

uint64_t PageWriter::writtenBatches() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return written_batches_;
}

PageWriter::Page PageWriter::find(const BlockKey& key) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = pending_.find(key);
  return it == pending_.end() ? nullptr : it->second.page;
}

void PageWriter::flush() {
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [this] { return (batches_.empty() && !writing_) || failed_; });
}

void PageWriter::releaseWritten() {
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto it = pending_.begin(); it != pending_.end();) {
    if (it->second.batch < written_batches_) {
      pending_bytes_ -= it->second.page->size();
      it = pending_.erase(it);
    } else {
      ++it;
    }
  }
}

size_t PageWriter::pendingBytes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return pending_bytes_;
}

bool PageWriter::failedKeys(std::vector<BlockKey>* keys, std::string* error) const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!failed_) return false;
  keys->clear();
  for (const auto& [key, pending] : pending_)
    if (pending.batch >= written_batches_) keys->push_back(key);
  *error = error_;
  return true;
}

void PageWriter::forgetFailed() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!failed_) return;
  for (auto it = pending_.begin(); it != pending_.end();) {
    if (it->second.batch >= written_batches_) {
      pending_bytes_ -= it->second.page->size();
      it = pending_.erase(it);
    } else {
      ++it;
    }
  }
  written_batches_ = next_batch_;  // the refused ones count as gone
  batches_.clear();
  failed_ = false;  // later batches are tried again (after a reset, a load)
  error_.clear();
}

void PageWriter::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    work_.wait(lock, [this] { return stop_ || (!batches_.empty() && !failed_); });
    if (batches_.empty() || failed_) {
      if (stop_) return;
      continue;
    }
    writing_ = true;
    const Batch& batch = batches_.front();  // only this thread pops; the host only appends
    lock.unlock();
    std::string error;
    bool written = false;
    if (batch.commit) {
      written = store_->commit(*batch.commit, &error);
    } else {
      std::vector<const std::vector<uint8_t>*> pages;
      pages.reserve(batch.pages.size());
      for (const Page& page : batch.pages) pages.push_back(page.get());
      written = store_->write(batch.keys, pages, &error);
    }
    lock.lock();
    writing_ = false;
    if (!written) {
      failed_ = true;  // this batch and every later one stay in pending_ for the host
      error_ = error;
    } else {
      // Its pages stay readable here until the host releases them (releaseWritten()).
      written_batches_ = batch.id + 1;
      batches_.pop_front();
    }
    done_.notify_all();
  }
}

}  // namespace stereo_fusion
