// An upload stream's chunks stored beside the stream (ChunkWriter), and resumed streams waiting
// for an earlier stream of their file (FilesBeingWritten).
#include <gtest/gtest.h>

#include <chrono>
#include <future>
#include <mutex>
#include <thread>

#include "server/services/chunk_writer.h"
#include "server/services/files_being_written.h"

namespace bathyslam::server {
namespace {

using namespace std::chrono_literals;
using Chunk = ChunkWriter::Chunk;

Chunk chunk_of(std::int64_t offset, std::size_t bytes) { return {offset, storage::Bytes(bytes, 7)}; }

// A store that records each transaction's chunks and waits `pause` in each.
struct RecordingStore {
  std::chrono::milliseconds pause{0};
  std::mutex mutex;
  std::vector<std::vector<std::int64_t>> batches;  // offsets per transaction
  std::int64_t committed = 0;

  storage::UploadState operator()(const std::vector<Chunk>& chunks) {
    std::this_thread::sleep_for(pause);
    std::lock_guard lock(mutex);
    batches.emplace_back();
    for (const Chunk& chunk : chunks) {
      if (chunk.offset != committed) throw storage::UploadError(storage::UploadError::Kind::kBadOffset, "offset");
      batches.back().push_back(chunk.offset);
      committed += static_cast<std::int64_t>(chunk.data.size());
    }
    storage::UploadState state;
    state.committed_bytes = committed;
    return state;
  }
  std::int64_t stored() {
    std::lock_guard lock(mutex);
    return committed;
  }
};

TEST(ChunkWriter, ASlowStreamsChunksAreStoredAsTheyComeNotAtItsEnd) {
  RecordingStore store;
  ChunkWriter writer([&](const std::vector<Chunk>& c) { return store(c); }, 100);
  for (std::int64_t k = 0; k < 3; ++k) {
    writer.add(chunk_of(10 * k, 10));
    // Stored while the stream is still open: a client cut now keeps it.
    const auto give_up = std::chrono::steady_clock::now() + 5s;
    while (store.stored() < 10 * (k + 1) && std::chrono::steady_clock::now() < give_up) std::this_thread::sleep_for(1ms);
    EXPECT_EQ(store.stored(), 10 * (k + 1));
  }
  EXPECT_EQ(writer.finish({}).committed_bytes, 30);
  EXPECT_EQ(store.batches.size(), 3u);
}

TEST(ChunkWriter, AFastStreamsChunksGoSeveralATransactionUpToABatch) {
  RecordingStore store;
  store.pause = 20ms;  // the database slower than the stream
  ChunkWriter writer([&](const std::vector<Chunk>& c) { return store(c); }, 40);
  for (std::int64_t k = 0; k < 20; ++k) writer.add(chunk_of(10 * k, 10));
  EXPECT_EQ(writer.finish({}).committed_bytes, 200);
  EXPECT_LT(store.batches.size(), 20u);
  for (const auto& batch : store.batches) EXPECT_LE(batch.size(), 4u);  // 40 bytes at most
}

TEST(ChunkWriter, ARefusalReachesTheStreamAndNothingAfterItIsStored) {
  RecordingStore store;
  ChunkWriter writer([&](const std::vector<Chunk>& c) { return store(c); }, 100);
  writer.add(chunk_of(0, 10));
  writer.add(chunk_of(15, 10));  // a gap: refused
  try {
    for (std::int64_t k = 0; k < 1000; ++k) {
      writer.add(chunk_of(25 + 10 * k, 10));
      std::this_thread::sleep_for(1ms);
    }
    writer.finish({});
    FAIL() << "the refusal was not passed on";
  } catch (const storage::UploadError& error) {
    EXPECT_EQ(error.kind(), storage::UploadError::Kind::kBadOffset);
  }
  EXPECT_EQ(store.stored(), 10);
}

TEST(FilesBeingWritten, ASecondStreamOfAFileWaitsForTheFirstAndAnotherFileDoesNot) {
  FilesBeingWritten files;
  auto first = std::make_unique<FilesBeingWritten::Mark>(files.mark_when_idle({1, "pings.csv"}, 10s));
  const auto started = std::chrono::steady_clock::now();
  files.mark_when_idle({1, "nav.csv"}, 10s);  // another file: at once
  files.mark_when_idle({2, "pings.csv"}, 10s);
  EXPECT_LT(std::chrono::steady_clock::now() - started, 1s);
  auto second = std::async(std::launch::async, [&] { files.wait_until_idle({1, "pings.csv"}, 10s); });
  EXPECT_EQ(second.wait_for(100ms), std::future_status::timeout);
  first.reset();
  EXPECT_EQ(second.wait_for(5s), std::future_status::ready);
  // A stream that never ends holds no one up for longer than the patience given.
  const auto held = files.mark_when_idle({3, "pings.csv"}, 10s);
  const auto waited_from = std::chrono::steady_clock::now();
  files.wait_until_idle({3, "pings.csv"}, 50ms);
  EXPECT_LT(std::chrono::steady_clock::now() - waited_from, 5s);
}

}  // namespace
}  // namespace bathyslam::server
