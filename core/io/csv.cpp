#include "core/io/csv.h"

#include <cstring>

namespace bathyslam {

LineTooLong::LineTooLong(std::size_t line, std::size_t max_bytes)
    : std::runtime_error("line longer than " + std::to_string(max_bytes) + " bytes; the rest of the file was not read"),
      line_(line) {}

LineReader::LineReader(ByteSource& source, std::size_t block_size, std::size_t max_line_bytes)
    : source_(source), max_line_bytes_(max_line_bytes), buffer_(block_size) {}

bool LineReader::refill() {
  if (eof_) return false;
  // Keep the unfinished line, then fill the rest of the buffer.
  const std::size_t carried = end_ - begin_;
  if (carried > max_line_bytes_ + 1) throw LineTooLong(line_number_ + 1, max_line_bytes_);  // + 1: a '\r'
  if (carried == buffer_.size()) buffer_.resize(buffer_.size() * 2);  // a very long line
  std::memmove(buffer_.data(), buffer_.data() + begin_, carried);
  begin_ = 0;
  end_ = carried;
  const std::size_t n = source_.read(buffer_.data() + end_, buffer_.size() - end_);
  if (n == 0) eof_ = true;
  end_ += n;
  return n > 0;
}

bool LineReader::next(std::string_view& line) {
  for (;;) {
    const char* start = buffer_.data() + begin_;
    const auto* newline = static_cast<const char*>(std::memchr(start, '\n', end_ - begin_));
    if (newline != nullptr) {
      std::size_t length = static_cast<std::size_t>(newline - start);
      begin_ += length + 1;
      if (length > 0 && start[length - 1] == '\r') --length;
      if (length > max_line_bytes_) throw LineTooLong(line_number_ + 1, max_line_bytes_);
      line = {start, length};
      ++line_number_;
      return true;
    }
    if (!refill()) {
      if (begin_ == end_) return false;
      // The last line has no newline.
      std::size_t length = end_ - begin_;
      const char* last = buffer_.data() + begin_;
      begin_ = end_;
      if (last[length - 1] == '\r') --length;
      if (length > max_line_bytes_) throw LineTooLong(line_number_ + 1, max_line_bytes_);
      line = {last, length};
      ++line_number_;
      return true;
    }
  }
}

std::size_t split_fields(std::string_view line, std::span<std::string_view> fields) {
  std::size_t count = 0;
  const char* p = line.data();
  const char* end = line.data() + line.size();
  for (;;) {
    const auto* comma = static_cast<const char*>(std::memchr(p, ',', end - p));
    const char* field_end = comma != nullptr ? comma : end;
    if (count < fields.size()) fields[count] = {p, static_cast<std::size_t>(field_end - p)};
    ++count;
    if (comma == nullptr) return count;
    p = comma + 1;
  }
}

std::string_view describe(NumberError error) {
  switch (error) {
    case NumberError::kNone: return "ok";
    case NumberError::kNotANumber: return "not a number";
    case NumberError::kNotFinite: return "not finite";
    case NumberError::kOutOfRange: return "out of range";
  }
  return "invalid";
}

}  // namespace bathyslam
