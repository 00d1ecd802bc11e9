#include <cerrno>
#include <charconv>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "core/io/bundle.h"
#include "core/io/file_bytes.h"

namespace bathyslam {
namespace detail {

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
      std::error_code ignored;  // a destructor must not throw; the partial file is only left behind
      std::filesystem::remove(partial_, ignored);
    }
  }
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;

  void text(std::string_view s) {
    if (file_ == nullptr) throw std::logic_error(path_.string() + ": written after commit");
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
    if (file_ == nullptr) throw std::logic_error(path_.string() + ": committed twice");
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

}  // namespace detail

using detail::AtomicFileWriter;

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

PingsCsvWriter::PingsCsvWriter(const std::filesystem::path& path) : out_(std::make_unique<AtomicFileWriter>(path)) {
  out_->text(kPingsHeader);
  out_->end_line();
}

PingsCsvWriter::~PingsCsvWriter() = default;

void PingsCsvWriter::add(double time, std::span<const Beam> beams) {
  char time_text[32];
  const auto [end, ec] = std::to_chars(time_text, time_text + sizeof time_text, time);
  const std::string_view time_field(time_text, end - time_text);
  for (const Beam& beam : beams) {
    out_->text(time_field);
    out_->separator(',');
    out_->number(beam.index);
    for (float v : {beam.along, beam.across, beam.down}) {
      out_->separator(',');
      out_->number(v);
    }
    out_->end_line();
  }
}

void PingsCsvWriter::commit() { out_->commit(); }

void write_bundle(const Survey& survey, const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  PingsCsvWriter pings(dir / kPingsFile);
  for (const Ping& ping : survey.pings) pings.add(ping.time, survey.beams_of(ping));
  pings.commit();
  write_bundle_without_pings(survey, dir);
}

void write_bundle_without_pings(const Survey& survey, const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  write_nav_csv(survey.nav, dir / kNavFile);
  if (survey.reference_nav) {
    write_nav_csv(*survey.reference_nav, dir / kReferenceNavFile);
  } else {
    std::filesystem::remove(dir / kReferenceNavFile);
  }
  // Last: a bundle with its survey.json is whole (scripts that reuse bundles look for it).
  const nlohmann::json json = {{"name", survey.metadata.name},
                               {"crs", survey.metadata.crs},
                               {"sonar", survey.metadata.sonar},
                               {"vehicle", survey.metadata.vehicle}};
  AtomicFileWriter json_out(dir / kSurveyJsonFile);
  json_out.text(json.dump(2));
  json_out.end_line();
  json_out.commit();
}

}  // namespace bathyslam
