#pragma once
// Big-endian integers, the only byte order GSF has (specification section 3.6.2): a bounds-checked
// cursor over a record's bytes for reading, and appending helpers for writing.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace bathyslam::gsf {

// Thrown when a field would run past the end of its record or subrecord; the reader turns it into
// a GsfError naming the byte offset in the file.
class OutOfBounds : public std::runtime_error {
 public:
  OutOfBounds(std::size_t position, std::size_t wanted, std::size_t size)
      : std::runtime_error("a " + std::to_string(wanted) + "-byte field at byte " + std::to_string(position) +
                           " runs past the end of its " + std::to_string(size) + "-byte (sub)record"),
        position_(position) {}
  std::size_t position() const { return position_; }

 private:
  std::size_t position_;
};

class BigEndianCursor {
 public:
  // `base` is where `bytes` start within the record, so positions in errors are record positions.
  explicit BigEndianCursor(std::span<const std::uint8_t> bytes, std::size_t base = 0) : bytes_(bytes), base_(base) {}

  std::size_t position() const { return base_ + pos_; }
  std::size_t remaining() const { return bytes_.size() - pos_; }

  std::uint8_t u8() { return take(1)[0]; }
  std::int8_t i8() { return static_cast<std::int8_t>(u8()); }
  std::uint16_t u16() {
    const std::uint8_t* p = take(2);
    return static_cast<std::uint16_t>((p[0] << 8) | p[1]);
  }
  std::int16_t i16() { return static_cast<std::int16_t>(u16()); }
  std::uint32_t u32() {
    const std::uint8_t* p = take(4);
    return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3];
  }
  std::int32_t i32() { return static_cast<std::int32_t>(u32()); }
  // GSF times: seconds and nanoseconds since 1970-01-01 UTC (section 3.6.6).
  double time() {
    const std::int32_t seconds = i32();
    const std::int32_t nanoseconds = i32();
    return static_cast<double>(seconds) + 1e-9 * static_cast<double>(nanoseconds);
  }
  std::string text(std::size_t size) {
    const std::uint8_t* p = take(size);
    std::string s(reinterpret_cast<const char*>(p), size);
    s.erase(s.find_last_not_of('\0') + 1);  // fixed-length text is NUL-padded
    return s;
  }
  void skip(std::size_t size) { take(size); }
  // The next `size` bytes as a cursor of their own (a subrecord).
  BigEndianCursor sub(std::size_t size) {
    const std::size_t start = position();
    const std::uint8_t* p = take(size);
    return BigEndianCursor({p, size}, start);
  }

 private:
  const std::uint8_t* take(std::size_t size) {
    if (size > remaining()) throw OutOfBounds(position(), size, bytes_.size());
    const std::uint8_t* p = bytes_.data() + pos_;
    pos_ += size;
    return p;
  }

  std::span<const std::uint8_t> bytes_;
  std::size_t base_ = 0;
  std::size_t pos_ = 0;
};

// A heading or course as GSF stores it: hundredths of a degree in [0, 36000). The wrap comes
// after rounding so that 359.999 is stored as 0, not as the out-of-range 36000.
inline std::uint16_t heading_field(double degrees) {
  const double hundredths = std::fmod(std::round(degrees * 100.0), 36000.0);
  return static_cast<std::uint16_t>(hundredths < 0 ? hundredths + 36000.0 : hundredths);
}

inline void put_u8(std::vector<std::uint8_t>& out, std::uint8_t v) { out.push_back(v); }
inline void put_u16(std::vector<std::uint8_t>& out, std::uint16_t v) {
  out.push_back(static_cast<std::uint8_t>(v >> 8));
  out.push_back(static_cast<std::uint8_t>(v));
}
inline void put_i16(std::vector<std::uint8_t>& out, std::int16_t v) { put_u16(out, static_cast<std::uint16_t>(v)); }
inline void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<std::uint8_t>(v >> shift));
}
inline void put_i32(std::vector<std::uint8_t>& out, std::int32_t v) { put_u32(out, static_cast<std::uint32_t>(v)); }
inline void patch_u16(std::vector<std::uint8_t>& out, std::size_t at, std::uint16_t v) {
  out[at] = static_cast<std::uint8_t>(v >> 8);
  out[at + 1] = static_cast<std::uint8_t>(v);
}
// Overwrites a u32 written earlier (a size known only once what follows is written).
inline void patch_u32(std::vector<std::uint8_t>& out, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out[at + i] = static_cast<std::uint8_t>(v >> (24 - 8 * i));
}

}  // namespace bathyslam::gsf
