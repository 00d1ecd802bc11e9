#include "server/services/chunk_writer.h"

#include <utility>

namespace bathyslam::server {

ChunkWriter::ChunkWriter(Store store, std::size_t batch_bytes)
    : store_(std::move(store)), batch_bytes_(batch_bytes), thread_([this] { run(); }) {}

ChunkWriter::~ChunkWriter() { store_the_rest(); }

void ChunkWriter::store_the_rest() {
  {
    std::lock_guard lock(mutex_);
    ending_ = true;
  }
  changed_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void ChunkWriter::add(Chunk chunk) {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [&] { return refusal_ || queued_bytes_ < 2 * batch_bytes_; });
  if (refusal_) std::rethrow_exception(refusal_);
  queued_bytes_ += chunk.data.size();
  queue_.push_back(std::move(chunk));
  changed_.notify_all();
}

storage::UploadState ChunkWriter::finish(storage::UploadState before) {
  store_the_rest();
  if (refusal_) std::rethrow_exception(refusal_);
  return stored_any_ ? last_ : before;
}

void ChunkWriter::run() {
  for (;;) {
    std::vector<Chunk> batch;
    {
      std::unique_lock lock(mutex_);
      changed_.wait(lock, [&] { return ending_ || !queue_.empty(); });
      if (queue_.empty() || refusal_) return;
      // Whatever arrived, up to a batch (always at least one chunk).
      std::size_t bytes = 0, take = 0;
      while (take < queue_.size() && (take == 0 || bytes + queue_[take].data.size() <= batch_bytes_))
        bytes += queue_[take++].data.size();
      batch.assign(std::make_move_iterator(queue_.begin()), std::make_move_iterator(queue_.begin() + take));
      queue_.erase(queue_.begin(), queue_.begin() + take);
      queued_bytes_ -= bytes;
    }
    changed_.notify_all();
    try {
      storage::UploadState state = store_(batch);
      std::lock_guard lock(mutex_);
      last_ = std::move(state);
      stored_any_ = true;
    } catch (...) {
      std::lock_guard lock(mutex_);
      refusal_ = std::current_exception();
      changed_.notify_all();
      return;
    }
  }
}

}  // namespace bathyslam::server
