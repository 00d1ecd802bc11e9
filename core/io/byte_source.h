#pragma once
// Where the bytes of an input file come from: a file on disk, or bytes already in memory
// (an upload held by the server). Parsers read through this so they never care which.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>

namespace bathyslam {

class ByteSource {
 public:
  virtual ~ByteSource() = default;
  // Copies up to `size` bytes into `buffer`; returns how many, 0 at the end.
  virtual std::size_t read(char* buffer, std::size_t size) = 0;
};

class FileSource : public ByteSource {
 public:
  // Reads from `offset` on. Throws std::runtime_error naming the file when it cannot be opened.
  explicit FileSource(const std::filesystem::path& path, std::uint64_t offset = 0);
  ~FileSource() override;
  FileSource(const FileSource&) = delete;
  FileSource& operator=(const FileSource&) = delete;
  std::size_t read(char* buffer, std::size_t size) override;

 private:
  std::FILE* file_;
};

class MemorySource : public ByteSource {
 public:
  explicit MemorySource(std::string_view bytes) : bytes_(bytes) {}
  std::size_t read(char* buffer, std::size_t size) override;

 private:
  std::string_view bytes_;
};

// Reads until `size` bytes or the end; returns how many (a source may return fewer per call).
std::size_t read_fully(ByteSource& source, char* buffer, std::size_t size);

// Replaces `bytes` (a std::string or a vector of bytes) with the next `size` bytes, or as many as
// the source has left; returns how many. `bytes` grows a MiB at a time as they arrive, so a record
// whose declared size runs past the end costs only what the file holds.
template <class Bytes>
std::size_t read_record(ByteSource& source, std::size_t size, Bytes& bytes) {
  constexpr std::size_t kStep = 1u << 20;
  bytes.clear();
  while (bytes.size() < size) {
    const std::size_t have = bytes.size(), want = std::min(kStep, size - have);
    bytes.resize(have + want);
    const std::size_t n = read_fully(source, reinterpret_cast<char*>(bytes.data() + have), want);
    if (n < want) {
      bytes.resize(have + n);
      break;
    }
  }
  return bytes.size();
}

// Reads a whole source into a string (for small files such as survey.json).
std::string read_all(ByteSource& source);
// The same, but stops after `max_bytes` + 1 bytes: enough to tell that the source is too large
// without holding all of it.
std::string read_at_most(ByteSource& source, std::size_t max_bytes);

}  // namespace bathyslam
