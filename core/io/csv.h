#pragma once
// A small, fast CSV scanner for the bundle's numeric tables: lines come out of fixed-size
// blocks (memory stays flat however large the file), fields are split on commas without
// quoting (the bundle's tables hold only numbers), and numbers parse with std::from_chars.
#include <charconv>
#include <cmath>
#include <cstddef>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "core/io/byte_source.h"

namespace bathyslam {

// A line longer than the reader allows: a file that is no table of numbers (or a hostile one
// without a newline, which would otherwise be held in memory whole).
class LineTooLong : public std::runtime_error {
 public:
  LineTooLong(std::size_t line, std::size_t max_bytes);
  std::size_t line() const { return line_; }

 private:
  std::size_t line_;
};

class LineReader {
 public:
  // A bundle's rows are under 200 bytes; 64 KiB leaves room for anything legitimate.
  static constexpr std::size_t kMaxLineBytes = 64 << 10;

  // Throws LineTooLong from next() at a line over `max_line_bytes`.
  explicit LineReader(ByteSource& source, std::size_t block_size = 4 << 20, std::size_t max_line_bytes = kMaxLineBytes);

  // The next line without its line ending ("\n" or "\r\n"); false at the end of input.
  bool next(std::string_view& line);
  // 1-based number of the line last returned.
  std::size_t line_number() const { return line_number_; }

 private:
  bool refill();

  ByteSource& source_;
  std::size_t max_line_bytes_;
  std::vector<char> buffer_;
  std::size_t begin_ = 0;  // first unread byte in buffer_
  std::size_t end_ = 0;    // one past the last valid byte in buffer_
  bool eof_ = false;
  std::size_t line_number_ = 0;
};

// Splits `line` on commas into `fields`; returns the number of fields found, which may exceed
// fields.size() (the extra fields are not stored).
std::size_t split_fields(std::string_view line, std::span<std::string_view> fields);

enum class NumberError { kNone, kNotANumber, kNotFinite, kOutOfRange };

template <typename T>
NumberError parse_number(std::string_view text, T& value) {
  const char* first = text.data();
  const char* last = text.data() + text.size();
  const auto [end, ec] = std::from_chars(first, last, value);
  if (ec == std::errc::result_out_of_range) return NumberError::kOutOfRange;
  if (ec != std::errc() || end != last) return NumberError::kNotANumber;
  if constexpr (std::is_floating_point_v<T>) {
    if (!std::isfinite(value)) return NumberError::kNotFinite;
  }
  return NumberError::kNone;
}

std::string_view describe(NumberError error);

}  // namespace bathyslam
