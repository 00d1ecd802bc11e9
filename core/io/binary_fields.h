#pragma once
// Fields of a binary record read one after another, bounds-checked, in the record's byte order:
// what the sonar-format readers (Kongsberg .all little-endian, XTF little-endian with R2Sonic's
// big-endian packets inside) share. A field past the record's end throws BadField naming it; the
// reader adds the file and the offset.
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

namespace bathyslam {

// A field that is not what the format allows.
struct BadField {
  std::string field, what;
};

enum class ByteOrder { kLittle, kBig };

class FieldCursor {
 public:
  // Reads `bytes` from `at` on; fields must end by `end` (exclusive).
  FieldCursor(std::string_view bytes, std::size_t at, std::size_t end, ByteOrder order)
      : bytes_(bytes), end_(end < bytes.size() ? end : bytes.size()), order_(order) {
    at_ = at < end_ ? at : end_;  // a start past the end reads nothing
  }

  std::uint8_t u8(const char* field) { return static_cast<std::uint8_t>(take(1, field)[0]); }
  std::uint16_t u16(const char* field) { return static_cast<std::uint16_t>(unsigned_of(2, field)); }
  std::int16_t i16(const char* field) { return static_cast<std::int16_t>(u16(field)); }
  std::uint32_t u32(const char* field) { return static_cast<std::uint32_t>(unsigned_of(4, field)); }
  std::int32_t i32(const char* field) { return static_cast<std::int32_t>(u32(field)); }
  float f32(const char* field) {
    const std::uint32_t bits = u32(field);
    float value;
    std::memcpy(&value, &bits, sizeof value);
    return value;
  }
  double f64(const char* field) {
    const std::uint64_t bits = unsigned_of(8, field);
    double value;
    std::memcpy(&value, &bits, sizeof value);
    return value;
  }
  // `n` bytes of text, cut at the first NUL.
  std::string text(std::size_t n, const char* field) {
    const char* p = take(n, field);
    return std::string(p, strnlen(p, n));
  }
  void skip(std::size_t n, const char* field) { take(n, field); }
  std::size_t position() const { return at_; }
  std::size_t left() const { return end_ - at_; }

 private:
  const char* take(std::size_t n, const char* field) {
    if (n > end_ - at_) {
      throw BadField{field, "runs past the end of its record (" + std::to_string(end_ - at_) + " bytes left)"};
    }
    const char* p = bytes_.data() + at_;
    at_ += n;
    return p;
  }
  std::uint64_t unsigned_of(std::size_t n, const char* field) {
    const auto* p = reinterpret_cast<const unsigned char*>(take(n, field));
    std::uint64_t v = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t k = order_ == ByteOrder::kLittle ? n - 1 - i : i;
      v = (v << 8) | p[k];
    }
    return v;
  }
  std::string_view bytes_;
  std::size_t at_, end_;
  ByteOrder order_;
};

// Days from 1970-01-01 to a civil date (Howard Hinnant's algorithm).
inline std::int64_t days_from_civil(int y, int m, int d) {
  y -= m <= 2;
  const int era = (y >= 0 ? y : y - 399) / 400;
  const int yoe = y - era * 400;
  const int doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const int doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return static_cast<std::int64_t>(era) * 146097 + doe - 719468;
}

}  // namespace bathyslam
