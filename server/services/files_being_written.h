#pragma once
// The files that upload streams are storing on this server. A stream keeps storing what it
// received after its client is gone (ChunkWriter), so a client that resumes at once would be told
// a committed size older than the one about to be stored, and its first chunk then refused:
// where to resume is answered, and a new stream of the file begins, once the earlier stream of
// the same file has stored what it had. Counted in memory, per server process.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <utility>

namespace bathyslam::server {

class FilesBeingWritten {
 public:
  using Key = std::pair<std::int64_t, std::string>;  // survey id, file name

  // A stream's mark on its file, taken off when the Mark goes.
  class Mark {
   public:
    Mark(FilesBeingWritten& files, Key key) : files_(&files), key_(std::move(key)) {}
    Mark(Mark&& other) noexcept : files_(other.files_), key_(std::move(other.key_)) { other.files_ = nullptr; }
    Mark(const Mark&) = delete;
    Mark& operator=(const Mark&) = delete;
    Mark& operator=(Mark&&) = delete;
    ~Mark() {
      if (files_) files_->unmark(key_);
    }

   private:
    FilesBeingWritten* files_;
    Key key_;
  };

  // Waits until no stream marks the file (at most `patience`: a stream whose client stalled
  // without closing holds no one up for long), then marks it for the caller's stream.
  Mark mark_when_idle(const Key& file, std::chrono::milliseconds patience);
  // Waits as mark_when_idle, without marking.
  void wait_until_idle(const Key& file, std::chrono::milliseconds patience);

 private:
  void unmark(const Key& file);

  std::mutex mutex_;
  std::condition_variable unmarked_;
  std::map<Key, int> streams_;
};

}  // namespace bathyslam::server
