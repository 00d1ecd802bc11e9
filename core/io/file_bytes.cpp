#include "core/io/file_bytes.h"

#include <cerrno>
#include <cstring>
#include <string>

namespace bathyslam {

WriteError::WriteError(const std::filesystem::path& path, int error_number)
    : std::runtime_error(path.string() + ": cannot write: " + std::strerror(error_number)),
      error_number_(error_number) {}

bool WriteError::out_of_space() const {
  return error_number_ == ENOSPC || error_number_ == EDQUOT || error_number_ == EFBIG;
}

void close_checked(std::ofstream& out, const std::filesystem::path& path) {
  // The stream keeps no error number of its own: errno is what the failing open(2), write(2) or
  // close(2) left, read at once (a stream that failed earlier leaves it to chance, hence EIO).
  if (out && out.is_open()) {
    errno = 0;
    out.close();  // flushes the buffered tail; failbit when that or close(2) fails
  }
  const int error = errno;
  if (!out) throw WriteError(path, error != 0 ? error : EIO);
}

void write_file_bytes(const std::filesystem::path& path, std::span<const std::uint8_t> bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  close_checked(out, path);
}

}  // namespace bathyslam
