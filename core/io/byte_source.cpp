#include "core/io/byte_source.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace bathyslam {

FileSource::FileSource(const std::filesystem::path& path, std::uint64_t offset)
    : file_(std::fopen(path.c_str(), "rb")) {
  if (file_ == nullptr) {
    throw std::runtime_error(path.string() + ": cannot open: " + std::strerror(errno));
  }
  if (offset > 0 && std::fseek(file_, static_cast<long>(offset), SEEK_SET) != 0) {
    const std::string why = std::strerror(errno);
    std::fclose(file_);
    throw std::runtime_error(path.string() + ": cannot seek to " + std::to_string(offset) + ": " + why);
  }
}

FileSource::~FileSource() { std::fclose(file_); }

std::size_t FileSource::read(char* buffer, std::size_t size) {
  return std::fread(buffer, 1, size, file_);
}

std::size_t MemorySource::read(char* buffer, std::size_t size) {
  const std::size_t n = std::min(size, bytes_.size());
  std::memcpy(buffer, bytes_.data(), n);
  bytes_.remove_prefix(n);
  return n;
}

std::size_t read_fully(ByteSource& source, char* buffer, std::size_t size) {
  std::size_t done = 0;
  while (done < size) {
    const std::size_t n = source.read(buffer + done, size - done);
    if (n == 0) break;
    done += n;
  }
  return done;
}

std::string read_all(ByteSource& source) {
  std::string out;
  char buffer[1 << 16];
  while (const std::size_t n = source.read(buffer, sizeof buffer)) out.append(buffer, n);
  return out;
}

std::string read_at_most(ByteSource& source, std::size_t max_bytes) {
  std::string out;
  char buffer[1 << 16];
  while (out.size() <= max_bytes) {
    const std::size_t n = source.read(buffer, std::min(sizeof buffer, max_bytes + 1 - out.size()));
    if (n == 0) break;
    out.append(buffer, n);
  }
  return out;
}

}  // namespace bathyslam
