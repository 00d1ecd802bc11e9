#include "server/services/files_being_written.h"

namespace bathyslam::server {

FilesBeingWritten::Mark FilesBeingWritten::mark_when_idle(const Key& file, std::chrono::milliseconds patience) {
  std::unique_lock lock(mutex_);
  unmarked_.wait_for(lock, patience, [&] { return !streams_.contains(file); });
  ++streams_[file];
  return Mark(*this, file);
}

void FilesBeingWritten::wait_until_idle(const Key& file, std::chrono::milliseconds patience) {
  std::unique_lock lock(mutex_);
  unmarked_.wait_for(lock, patience, [&] { return !streams_.contains(file); });
}

void FilesBeingWritten::unmark(const Key& file) {
  {
    std::lock_guard lock(mutex_);
    if (--streams_[file] == 0) streams_.erase(file);
  }
  unmarked_.notify_all();
}

}  // namespace bathyslam::server
