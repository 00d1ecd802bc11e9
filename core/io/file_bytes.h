#pragma once
// Whole-file writes of encoded bytes (PNG and the like), and the check every writer of a file
// ends with: a write the disk refused is a WriteError, never a quietly shorter file.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <span>
#include <stdexcept>

namespace bathyslam {

// A file that could not be written whole: the disk is full, over quota or failing. The
// machine's fault, not the data's, so a server answers it as a shortage of resources and never
// records it as a verdict about what was being written.
class WriteError : public std::runtime_error {
 public:
  // `error_number`: the errno of the failure (EIO when the stream kept none).
  WriteError(const std::filesystem::path& path, int error_number);
  int error_number() const { return error_number_; }
  bool out_of_space() const;  // ENOSPC, EDQUOT or EFBIG: freeing space helps

 private:
  int error_number_;
};

// Flushes and closes `out`, which writes `path`; throws WriteError unless every byte written to
// it reached the file. Needed because an ofstream holds its last bytes until it closes, and its
// destructor drops a failure to write them without a word.
void close_checked(std::ofstream& out, const std::filesystem::path& path);

// Writes `bytes` to `path`, replacing it; throws WriteError naming the path on failure.
void write_file_bytes(const std::filesystem::path& path, std::span<const std::uint8_t> bytes);

}  // namespace bathyslam
