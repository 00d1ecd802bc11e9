#pragma once
// An upload stream's chunks stored on a thread of their own while the stream goes on: each
// transaction takes every chunk that arrived since the last one (up to a batch). A fast client's
// chunks go a batch a transaction (one per chunk left the CPU half idle on round trips); a slow
// client's each as it comes, so a stream cut at any moment has kept what it delivered.
#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "server/storage/survey_store.h"

namespace bathyslam::server {

class ChunkWriter {
 public:
  using Chunk = storage::SurveyStore::Chunk;
  // Stores chunks that follow each other, as SurveyStore::append_chunks does.
  using Store = std::function<storage::UploadState(const std::vector<Chunk>&)>;

  // At most `batch_bytes` a transaction; `add` waits while twice that is queued.
  ChunkWriter(Store store, std::size_t batch_bytes);
  ~ChunkWriter();  // stores what is queued (a refusal then is dropped) and joins
  ChunkWriter(const ChunkWriter&) = delete;
  ChunkWriter& operator=(const ChunkWriter&) = delete;

  // Queues a chunk; throws the refusal of a chunk stored before it, if any.
  void add(Chunk chunk);
  // Stores what is queued and returns the upload's state after the last transaction (`before`
  // when there was none); throws the first refusal.
  storage::UploadState finish(storage::UploadState before);

 private:
  void run();
  void store_the_rest();  // and joins the thread

  Store store_;
  std::size_t batch_bytes_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<Chunk> queue_;
  std::size_t queued_bytes_ = 0;
  bool ending_ = false, stored_any_ = false;
  storage::UploadState last_;
  std::exception_ptr refusal_;
  std::thread thread_;  // last: starts once the rest is made
};

}  // namespace bathyslam::server
