#include "core/io/gsf/gsf_writer.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "core/io/file_bytes.h"
#include "core/io/gsf/big_endian.h"

namespace bathyslam::gsf {
namespace {

struct ArrayEncoding {
  std::uint8_t id;
  const char* name;
  int width;  // bytes
  bool is_signed;
  std::int32_t multiplier;
};

// Tenths of a millimetre: finer than float32 keeps an across-track distance of a kilometre, so
// the arrays add no loss of their own, and 4 bytes still reach 214 km (429 km of depth).
constexpr ArrayEncoding kDepth{kDepthArray, "depth", 4, false, 10000};
constexpr ArrayEncoding kAcross{kAcrossTrackArray, "across-track", 4, true, 10000};
constexpr ArrayEncoding kAlong{kAlongTrackArray, "along-track", 4, true, 10000};
constexpr ArrayEncoding kTravelTime{kTravelTimeArray, "travel time", 4, false, 1000000};
constexpr ArrayEncoding kBeamAngle{kBeamAngleArray, "beam angle", 2, true, 100};

// Rounds `value` to an integer field of `width` bytes; throws naming the field when it does not fit.
std::int64_t to_field(double value, double multiplier, int width, bool is_signed, const std::string& what) {
  const double scaled = std::round(value * multiplier);
  const double bits = 8.0 * width;
  const double lo = is_signed ? -std::ldexp(1.0, static_cast<int>(bits) - 1) : 0.0;
  const double hi = is_signed ? std::ldexp(1.0, static_cast<int>(bits) - 1) - 1 : std::ldexp(1.0, static_cast<int>(bits)) - 1;
  if (!(scaled >= lo && scaled <= hi)) {
    throw std::runtime_error(what + " " + std::to_string(value) + " does not fit its " + std::to_string(width) +
                             "-byte GSF field");
  }
  return static_cast<std::int64_t>(scaled);
}

void put_time(std::vector<std::uint8_t>& out, double time) {
  double seconds = std::floor(time);
  double nanoseconds = std::round((time - seconds) * 1e9);
  if (nanoseconds >= 1e9) {
    seconds += 1;
    nanoseconds -= 1e9;
  }
  put_i32(out, static_cast<std::int32_t>(seconds));
  put_i32(out, static_cast<std::int32_t>(nanoseconds));
}

void put_array(std::vector<std::uint8_t>& out, const ArrayEncoding& e, const std::vector<double>& values,
               const std::string& what) {
  put_u32(out, (std::uint32_t{e.id} << 24) | static_cast<std::uint32_t>(values.size() * e.width));
  for (double v : values) {
    const std::int64_t field = to_field(v, e.multiplier, e.width, e.is_signed, what);
    if (e.width == 2) put_u16(out, static_cast<std::uint16_t>(field));
    else put_u32(out, static_cast<std::uint32_t>(field));
  }
}

}  // namespace

Writer::Writer(const std::filesystem::path& path, const std::string& version)
    : path_(path), temporary_(path.string() + ".partial") {
  out_.open(temporary_, std::ios::binary | std::ios::trunc);
  if (!out_) close_checked(out_, temporary_);
  std::vector<std::uint8_t> header(version.begin(), version.end());
  header.resize(12, 0);  // the version field is 12 characters, NUL-padded
  write_record(kHeader, header);
}

Writer::~Writer() {
  if (!closed_) {
    out_.close();
    std::error_code ignored;
    std::filesystem::remove(temporary_, ignored);
  }
}

void Writer::write_raw(std::uint32_t id, std::vector<std::uint8_t> data) { write_record(id, data); }

void Writer::write_record(std::uint32_t id, std::vector<std::uint8_t>& data) {
  while (data.size() % 4 != 0) data.push_back(0);  // records are whole 4-byte words
  std::vector<std::uint8_t> framing;
  put_u32(framing, static_cast<std::uint32_t>(data.size()));
  put_u32(framing, id);
  if ((id >> 31) != 0) {  // checksum flag: the sum of the data bytes follows the identifier
    std::uint32_t sum = 0;
    for (std::uint8_t b : data) sum += b;
    put_u32(framing, sum);
  }
  out_.write(reinterpret_cast<const char*>(framing.data()), static_cast<std::streamsize>(framing.size()));
  out_.write(reinterpret_cast<const char*>(data.data()), static_cast<std::streamsize>(data.size()));
  if (!out_) close_checked(out_, temporary_);  // at once, while errno still says why
}

void Writer::write(const Comment& comment) {
  std::vector<std::uint8_t> data;
  put_time(data, comment.time);
  put_u32(data, static_cast<std::uint32_t>(comment.text.size()));
  data.insert(data.end(), comment.text.begin(), comment.text.end());
  write_record(kComment, data);
}

void Writer::write(const ProcessingParameters& parameters) {
  std::vector<std::uint8_t> data;
  put_time(data, parameters.time);
  put_i16(data, static_cast<std::int16_t>(parameters.parameters.size()));
  for (const std::string& p : parameters.parameters) {
    put_i16(data, static_cast<std::int16_t>(p.size()));
    data.insert(data.end(), p.begin(), p.end());
  }
  write_record(kProcessingParameters, data);
}

void Writer::write(const Ping& ping) {
  const std::string what = path_.string() + ": ping " + std::to_string(pings_ + 1) + ":";
  const auto n = static_cast<std::size_t>(ping.num_beams);
  const std::pair<const ArrayEncoding*, const std::vector<double>*> arrays[] = {
      {&kDepth, &ping.depth_m},           {&kAcross, &ping.across_m},        {&kAlong, &ping.along_m},
      {&kTravelTime, &ping.travel_time_s}, {&kBeamAngle, &ping.beam_angle_deg}};
  auto check_size = [&](std::size_t size, const char* name) {
    if (size != 0 && size != n) {
      throw std::runtime_error(what + " " + name + " array has " + std::to_string(size) + " values for " +
                               std::to_string(n) + " beams");
    }
  };
  for (const auto& [encoding, values] : arrays) check_size(values->size(), encoding->name);
  check_size(ping.beam_flags.size(), "beam flags");

  std::vector<std::uint8_t> data;
  put_time(data, ping.time);
  put_i32(data, static_cast<std::int32_t>(to_field(ping.longitude_deg, 1e7, 4, true, what + " longitude")));
  put_i32(data, static_cast<std::int32_t>(to_field(ping.latitude_deg, 1e7, 4, true, what + " latitude")));
  put_i16(data, static_cast<std::int16_t>(to_field(ping.num_beams, 1, 2, true, what + " number of beams")));
  put_i16(data, static_cast<std::int16_t>(ping.center_beam));
  put_u16(data, ping.flags);
  put_i16(data, 0);  // reserved
  put_i16(data, static_cast<std::int16_t>(to_field(ping.tide_corrector_m, 100, 2, true, what + " tide corrector")));
  put_i32(data, static_cast<std::int32_t>(to_field(ping.depth_corrector_m, 100, 4, true, what + " depth corrector")));
  put_u16(data, heading_field(ping.heading_deg));
  put_i16(data, static_cast<std::int16_t>(to_field(ping.pitch_deg, 100, 2, true, what + " pitch")));
  put_i16(data, static_cast<std::int16_t>(to_field(ping.roll_deg, 100, 2, true, what + " roll")));
  put_i16(data, static_cast<std::int16_t>(to_field(ping.heave_m, 100, 2, true, what + " heave")));
  put_u16(data, heading_field(ping.course_deg));
  put_u16(data, static_cast<std::uint16_t>(to_field(ping.speed_knots, 100, 2, false, what + " speed")));
  put_i32(data, 0);  // height above the ellipsoid: unknown
  put_i32(data, 0);  // separation
  put_i32(data, 0);  // GPS tide corrector
  put_i16(data, 0);  // spare

  std::vector<std::uint8_t> present;
  for (const auto& [encoding, values] : arrays) {
    if (!values->empty()) present.push_back(encoding->id);
  }
  if (!ping.beam_flags.empty()) present.push_back(kBeamFlagsArray);
  if (present != scaled_arrays_) {  // the first ping, or one with other arrays
    put_u32(data, (std::uint32_t{kScaleFactors} << 24) | static_cast<std::uint32_t>(4 + 12 * present.size()));
    put_i32(data, static_cast<std::int32_t>(present.size()));
    for (std::uint8_t id : present) {
      std::int32_t multiplier = 1;
      std::uint8_t compression = 0x10;
      for (const auto& [encoding, values] : arrays) {
        if (encoding->id == id) {
          multiplier = encoding->multiplier;
          compression = encoding->width == 4 ? 0x40 : 0x20;
        }
      }
      put_u8(data, id);
      put_u8(data, compression);
      put_u16(data, 0);
      put_i32(data, multiplier);
      put_i32(data, 0);  // offset
    }
    scaled_arrays_ = present;
  }
  for (const auto& [encoding, values] : arrays) {
    if (!values->empty()) put_array(data, *encoding, *values, what + " " + encoding->name);
  }
  if (!ping.beam_flags.empty()) {
    put_u32(data, (std::uint32_t{kBeamFlagsArray} << 24) | static_cast<std::uint32_t>(n));
    data.insert(data.end(), ping.beam_flags.begin(), ping.beam_flags.end());
  }
  write_record(kSwathBathymetryPing, data);
  ++pings_;
}

void Writer::close() {
  close_checked(out_, temporary_);
  std::filesystem::rename(temporary_, path_);
  closed_ = true;
}

}  // namespace bathyslam::gsf
