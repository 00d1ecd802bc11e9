#include <cerrno>
#include <charconv>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "core/io/bundle.h"
#include "core/io/file_bytes.h"

namespace bathyslam {
namespace {

// A file written through a large buffer under "<name>.partial", renamed into place on commit().
class AtomicFileWriter {
 public:
  explicit AtomicFileWriter(std::filesystem::path path)
      : path_(std::move(path)), partial_(path_.string() + ".partial") {
    file_ = std::fopen(partial_.c_str(), "wb");
    if (file_ == nullptr) fail();
    buffer_.reserve(kFlushAt + 256);
  }
  ~AtomicFileWriter() {
    if (file_ != nullptr) {
      std::fclose(file_);
      std::filesystem::remove(partial_);
    }
  }
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;

  void text(std::string_view s) {
    buffer_.append(s);
    if (buffer_.size() >= kFlushAt) flush();
  }
  void separator(char c) { buffer_.push_back(c); }
  template <typename T>
  void number(T value) {
    char digits[32];
    const auto [end, ec] = std::to_chars(digits, digits + sizeof digits, value);
    buffer_.append(digits, end);
  }
  void end_line() {
    buffer_.push_back('\n');
    if (buffer_.size() >= kFlushAt) flush();
  }

  void commit() {
    flush();
    if (std::fclose(file_) != 0) {
      file_ = nullptr;
      fail();
    }
    file_ = nullptr;
    std::filesystem::rename(partial_, path_);
  }

 private:
  static constexpr std::size_t kFlushAt = 1 << 20;

  void flush() {
    if (std::fwrite(buffer_.data(), 1, buffer_.size(), file_) != buffer_.size()) fail();
    buffer_.clear();
  }
  [[noreturn]] void fail() { throw WriteError(partial_, errno != 0 ? errno : EIO); }

  std::filesystem::path path_;
  std::filesystem::path partial_;
  std::FILE* file_ = nullptr;
  std::string buffer_;
};

}  // namespace

void write_nav_csv(const std::vector<NavSample>& nav, const std::filesystem::path& path) {
  AtomicFileWriter out(path);
  out.text(kNavHeader);
  out.end_line();
  for (const NavSample& s : nav) {
    out.number(s.time);
    for (double v : {s.easting, s.northing, s.depth_m, s.roll_deg, s.pitch_deg, s.heading_deg}) {
      out.separator(',');
      out.number(v);
    }
    out.end_line();
  }
  out.commit();
}

namespace {

void write_pings(const Survey& survey, const std::filesystem::path& path) {
  AtomicFileWriter out(path);
  out.text(kPingsHeader);
  out.end_line();
  char time_text[32];
  for (const Ping& ping : survey.pings) {
    const auto [end, ec] = std::to_chars(time_text, time_text + sizeof time_text, ping.time);
    const std::string_view time(time_text, end - time_text);
    for (const Beam& beam : survey.beams_of(ping)) {
      out.text(time);
      out.separator(',');
      out.number(beam.index);
      for (float v : {beam.along, beam.across, beam.down}) {
        out.separator(',');
        out.number(v);
      }
      out.end_line();
    }
  }
  out.commit();
}

}  // namespace

void write_bundle(const Survey& survey, const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  const nlohmann::json json = {{"name", survey.metadata.name},
                               {"crs", survey.metadata.crs},
                               {"sonar", survey.metadata.sonar},
                               {"vehicle", survey.metadata.vehicle}};
  AtomicFileWriter json_out(dir / kSurveyJsonFile);
  json_out.text(json.dump(2));
  json_out.end_line();
  json_out.commit();
  write_nav_csv(survey.nav, dir / kNavFile);
  write_pings(survey, dir / kPingsFile);
  if (survey.reference_nav) {
    write_nav_csv(*survey.reference_nav, dir / kReferenceNavFile);
  } else {
    std::filesystem::remove(dir / kReferenceNavFile);
  }
}

}  // namespace bathyslam
