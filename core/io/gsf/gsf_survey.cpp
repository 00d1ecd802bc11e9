#include "core/io/gsf/gsf_survey.h"

#include "core/io/file_extension.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <limits>
#include <memory>
#include <stdexcept>

#include <Eigen/Geometry>

#include "core/io/bundle.h"
#include "core/io/crs.h"
#include "core/io/gsf/big_endian.h"
#include "core/io/gsf/gsf_reader.h"
#include "core/io/gsf/gsf_writer.h"
#include "core/sync/nav_interpolation.h"
#include "core/types/pose.h"

namespace bathyslam::gsf {
namespace {

constexpr double kDegToRad = M_PI / 180.0;
// Metadata kept per survey is bounded: a file with a comment per ping must not grow the JSON.
constexpr std::size_t kMaxKeptComments = 100;
constexpr std::size_t kMaxKeptProfiles = 20;

// The rotation from the vehicle frame to GSF's level, heading-aligned frame.
Eigen::Matrix3d tilt(double roll_deg, double pitch_deg) { return vehicle_to_level_rotation(roll_deg, pitch_deg); }

Eigen::Matrix3d yaw(double heading_deg) {
  return Eigen::AngleAxisd(heading_deg * kDegToRad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

bool usable_beam(const Ping& ping, std::size_t beam) {
  return !ping.beam_rejected(beam) && beam < ping.depth_m.size() && beam < ping.across_m.size() &&
         std::isfinite(ping.depth_m[beam]) && std::isfinite(ping.across_m[beam]);
}

double along_of(const Ping& ping, std::size_t beam) { return ping.along_m.empty() ? 0.0 : ping.along_m[beam]; }

// The usable soundings of a usable ping, in the vehicle frame, appended to `beams`.
void append_soundings(const Ping& p, std::vector<Beam>& beams) {
  const Eigen::Matrix3d level_to_vehicle = tilt(p.roll_deg, p.pitch_deg).transpose();
  for (std::size_t b = 0; b < static_cast<std::size_t>(p.num_beams); ++b) {
    if (!usable_beam(p, b)) continue;
    const Eigen::Vector3d level(along_of(p, b), p.across_m[b], p.depth_m[b] - p.depth_corrector_m);
    const Eigen::Vector3d v = level_to_vehicle * level;
    beams.push_back({static_cast<std::uint32_t>(b), static_cast<float>(v.x()), static_cast<float>(v.y()),
                     static_cast<float>(v.z())});
  }
}

std::uint32_t usable_soundings(const Ping& p) {
  std::uint32_t n = 0;
  for (std::size_t b = 0; b < static_cast<std::size_t>(p.num_beams); ++b) n += usable_beam(p, b) ? 1 : 0;
  return n;
}

// Collects a file's summary record by record.
class SummaryBuilder {
 public:
  explicit SummaryBuilder(std::string file) { s_.file = std::move(file); }

  void add(const Record& record) {
    ++s_.records;
    if (const auto* h = std::get_if<Header>(&record)) s_.version = h->version;
    else if (const auto* p = std::get_if<Ping>(&record)) add_ping(*p);
    else if (const auto* a = std::get_if<Attitude>(&record)) {
      ++s_.attitude_records;
      s_.attitude_samples += a->time.size();
    } else if (std::holds_alternative<SoundVelocityProfile>(record)) ++s_.sound_velocity_profiles;
    else if (std::holds_alternative<ProcessingParameters>(record)) ++s_.processing_parameter_records;
    else if (std::holds_alternative<Comment>(record)) ++s_.comments;
    else ++s_.skipped_records;
  }

  FileSummary finish(std::uint64_t bytes) {
    s_.bytes = bytes;
    if (s_.soundings == 0) s_.depth_min_m = s_.depth_max_m = 0;
    return s_;
  }

 private:
  void add_ping(const Ping& p) {
    const bool first = s_.pings == 0;
    ++s_.pings;
    auto widen = [first](double& lo, double& hi, double v) {
      lo = first ? v : std::min(lo, v);
      hi = first ? v : std::max(hi, v);
    };
    widen(s_.time_begin, s_.time_end, p.time);
    widen(s_.latitude_min, s_.latitude_max, p.latitude_deg);
    widen(s_.longitude_min, s_.longitude_max, p.longitude_deg);
    s_.min_beams_per_ping = first ? p.num_beams : std::min(s_.min_beams_per_ping, p.num_beams);
    s_.max_beams_per_ping = std::max(s_.max_beams_per_ping, p.num_beams);
    if (p.ignored()) {
      ++s_.ignored_pings;
      return;
    }
    s_.beams += static_cast<std::uint64_t>(p.num_beams);
    for (std::size_t b = 0; b < static_cast<std::size_t>(p.num_beams); ++b) {
      if (!usable_beam(p, b)) {
        ++s_.rejected_beams;
        continue;
      }
      const double depth = p.depth_m[b];
      s_.depth_min_m = s_.soundings == 0 ? depth : std::min(s_.depth_min_m, depth);
      s_.depth_max_m = s_.soundings == 0 ? depth : std::max(s_.depth_max_m, depth);
      ++s_.soundings;
    }
  }

  FileSummary s_;
};

std::string iso_time(double t) {
  const auto seconds = static_cast<std::time_t>(std::floor(t));
  std::tm tm{};
  gmtime_r(&seconds, &tm);
  char buffer[400];
  std::snprintf(buffer, sizeof buffer, "%04d-%02d-%02dT%02d:%02d:%06.3fZ", tm.tm_year + 1900, tm.tm_mon + 1,
                tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec + (t - std::floor(t)));
  return buffer;
}

// Appends one ping's navigation and usable soundings to `survey`.
class SurveyBuilder {
 public:
  SurveyBuilder(Survey& survey, std::string crs, bool keep_soundings)
      : survey_(survey), crs_(std::move(crs)), keep_soundings_(keep_soundings) {}

  void add(const Ping& p, const std::string& where) {
    if (!projection_) {
      if (crs_.empty()) crs_ = utm_crs_of(p.longitude_deg, p.latitude_deg);
      if (const auto problem = crs_problem(crs_)) throw std::runtime_error(*problem);
      projection_ = std::make_unique<GeographicProjection>(crs_);
      survey_.metadata.crs = crs_;
    }
    if (!survey_.nav.empty() && p.time < survey_.nav.back().time) {
      throw std::runtime_error(where + ": ping at " + iso_time(p.time) + " is earlier than the one before (" +
                               iso_time(survey_.nav.back().time) + "); give the files in time order");
    }
    const auto en = projection_->forward(p.longitude_deg, p.latitude_deg);
    if (!std::isfinite(en.easting) || !std::isfinite(en.northing)) {
      throw std::runtime_error(where + ": cannot project the ping's position into " + crs_);
    }
    // Two pings at one time (dual-head sonars) share one navigation sample.
    if (survey_.nav.empty() || p.time > survey_.nav.back().time) {
      survey_.nav.push_back({p.time, en.easting, en.northing, p.depth_corrector_m, p.roll_deg, p.pitch_deg,
                             p.heading_deg});
    }
    if (p.ignored()) return;
    bathyslam::Ping ping{p.time, static_cast<std::uint32_t>(survey_.beams.size()), 0};
    if (keep_soundings_) {
      append_soundings(p, survey_.beams);
      ping.beam_count = static_cast<std::uint32_t>(survey_.beams.size()) - ping.first_beam;
    } else {
      ping.beam_count = usable_soundings(p);
    }
    if (ping.beam_count > 0) survey_.pings.push_back(ping);
  }

 private:
  Survey& survey_;
  std::string crs_;
  bool keep_soundings_;
  std::unique_ptr<GeographicProjection> projection_;
};

// The metadata a hydrographer wants kept: sound velocity profiles, processing parameters, comments.
class MetadataBuilder {
 public:
  void add(const Record& record) {
    if (const auto* svp = std::get_if<SoundVelocityProfile>(&record)) {
      if (profiles_.size() >= kMaxKeptProfiles) return;
      nlohmann::json points = nlohmann::json::array();
      for (std::size_t i = 0; i < svp->depth_m.size(); ++i) points.push_back({svp->depth_m[i], svp->sound_velocity_m_s[i]});
      profiles_.push_back({{"observed", iso_time(svp->observed_time)},
                           {"applied", iso_time(svp->applied_time)},
                           {"longitude_deg", svp->longitude_deg},
                           {"latitude_deg", svp->latitude_deg},
                           {"depth_m_sound_velocity_m_s", points}});
    } else if (const auto* pp = std::get_if<ProcessingParameters>(&record)) {
      for (const std::string& p : pp->parameters) {
        const auto eq = p.find('=');
        if (eq == std::string::npos) parameters_[p] = "";
        else parameters_[p.substr(0, eq)] = p.substr(eq + 1);
      }
    } else if (const auto* c = std::get_if<Comment>(&record)) {
      if (comments_.size() < kMaxKeptComments) comments_.push_back(c->text);
    }
  }

  nlohmann::json json(const std::vector<FileSummary>& files) const {
    nlohmann::json summaries = nlohmann::json::array();
    for (const FileSummary& f : files) summaries.push_back(to_json(f));
    return {{"format", "GSF"},
            {"files", summaries},
            {"sound_velocity_profiles", profiles_},
            {"processing_parameters", parameters_},
            {"comments", comments_}};
  }

 private:
  nlohmann::json profiles_ = nlohmann::json::array();
  nlohmann::json parameters_ = nlohmann::json::object();
  nlohmann::json comments_ = nlohmann::json::array();
};

}  // namespace

nlohmann::json to_json(const FileSummary& s) {
  return {{"file", s.file},
          {"version", s.version},
          {"bytes", s.bytes},
          {"records", s.records},
          {"pings", s.pings},
          {"ignored_pings", s.ignored_pings},
          {"beams_per_ping_min", s.min_beams_per_ping},
          {"beams_per_ping_max", s.max_beams_per_ping},
          {"beams", s.beams},
          {"soundings", s.soundings},
          {"rejected_beams", s.rejected_beams},
          {"attitude_records", s.attitude_records},
          {"attitude_samples", s.attitude_samples},
          {"sound_velocity_profiles", s.sound_velocity_profiles},
          {"processing_parameter_records", s.processing_parameter_records},
          {"comments", s.comments},
          {"skipped_records", s.skipped_records},
          {"time_begin", iso_time(s.time_begin)},
          {"time_end", iso_time(s.time_end)},
          {"latitude_deg", {s.latitude_min, s.latitude_max}},
          {"longitude_deg", {s.longitude_min, s.longitude_max}},
          {"depth_m", {s.depth_min_m, s.depth_max_m}}};
}

std::string to_text(const FileSummary& s) {
  char buffer[1024];
  std::snprintf(buffer, sizeof buffer,
                "%s: %s, %llu bytes, %llu records\n"
                "  pings       %llu (%llu ignored), %d-%d beams per ping\n"
                "  soundings   %llu of %llu beams (%llu rejected)\n"
                "  time        %s .. %s\n"
                "  latitude    %.5f .. %.5f\n"
                "  longitude   %.5f .. %.5f\n"
                "  depth       %.1f .. %.1f m\n"
                "  attitude    %llu records, %llu samples\n"
                "  metadata    %llu sound velocity profiles, %llu processing parameter records, %llu comments, "
                "%llu other records skipped\n",
                s.file.c_str(), s.version.c_str(), static_cast<unsigned long long>(s.bytes),
                static_cast<unsigned long long>(s.records), static_cast<unsigned long long>(s.pings),
                static_cast<unsigned long long>(s.ignored_pings), s.min_beams_per_ping, s.max_beams_per_ping,
                static_cast<unsigned long long>(s.soundings), static_cast<unsigned long long>(s.beams),
                static_cast<unsigned long long>(s.rejected_beams), iso_time(s.time_begin).c_str(),
                iso_time(s.time_end).c_str(), s.latitude_min, s.latitude_max, s.longitude_min, s.longitude_max,
                s.depth_min_m, s.depth_max_m, static_cast<unsigned long long>(s.attitude_records),
                static_cast<unsigned long long>(s.attitude_samples),
                static_cast<unsigned long long>(s.sound_velocity_profiles),
                static_cast<unsigned long long>(s.processing_parameter_records),
                static_cast<unsigned long long>(s.comments), static_cast<unsigned long long>(s.skipped_records));
  return buffer;
}

FileSummary summarize_file(ByteSource& source, const std::string& file) {
  Reader reader(source, file);
  SummaryBuilder summary(file);
  while (const auto record = reader.next()) summary.add(*record);
  return summary.finish(reader.bytes_read());
}

SurveyRead read_survey(const std::vector<std::filesystem::path>& files, const ReadOptions& options) {
  if (files.empty()) throw std::runtime_error("no GSF file given");
  SurveyRead out;
  out.survey.metadata.name = files.front().stem().string();
  SurveyBuilder survey(out.survey, options.crs, options.keep_soundings);
  MetadataBuilder metadata;
  for (const std::filesystem::path& path : files) {
    FileSource source(path);
    Reader reader(source, path.string());
    SummaryBuilder summary(path.filename().string());
    while (const auto record = reader.next()) {
      summary.add(*record);
      metadata.add(*record);
      if (const auto* ping = std::get_if<Ping>(&*record)) {
        survey.add(*ping, path.string() + ": record " + std::to_string(reader.records_read()));
      }
    }
    out.files.push_back(summary.finish(reader.bytes_read()));
  }
  if (out.survey.pings.empty()) {
    throw std::runtime_error(files.front().string() + ": no usable ping with soundings");
  }
  out.survey.metadata.sonar = metadata.json(out.files);
  if (options.reference_nav) out.survey.reference_nav = read_reference_nav(*options.reference_nav);
  return out;
}

void stream_soundings(const std::vector<std::filesystem::path>& files, Survey& survey, PingSink& sink) {
  sink.begin(survey);
  std::vector<Beam> beams;
  std::size_t next = 0;  // the ping of `survey` the files' next usable ping must be
  for (const std::filesystem::path& path : files) {
    FileSource source(path);
    Reader reader(source, path.string());
    while (const auto record = reader.next()) {
      const auto* p = std::get_if<Ping>(&*record);
      if (p == nullptr || p->ignored()) continue;
      beams.clear();
      append_soundings(*p, beams);
      if (beams.empty()) continue;
      if (next == survey.pings.size() || survey.pings[next].time != p->time ||
          survey.pings[next].beam_count != beams.size()) {
        throw std::runtime_error(path.string() + ": record " + std::to_string(reader.records_read()) +
                                 ": the file changed while it was read");
      }
      sink.ping(p->time, beams);
      ++next;
    }
  }
  if (next != survey.pings.size()) {
    throw std::runtime_error((files.empty() ? std::string("the GSF files") : files.back().string()) +
                             ": the file changed while it was read");
  }
  std::vector<bathyslam::Ping>().swap(survey.pings);
  std::vector<Beam>().swap(survey.beams);
}

SurveyWriter::SurveyWriter(const std::filesystem::path& path, std::vector<NavSample> nav)
    : nav_(std::move(nav)), writer_(std::make_unique<Writer>(path)) {}

SurveyWriter::~SurveyWriter() = default;

void SurveyWriter::begin(const Survey& survey) {
  projection_ = std::make_unique<GeographicProjection>(survey.metadata.crs);
  comment_ = "bathyslam survey '" + survey.metadata.name + "', navigation in " + survey.metadata.crs +
             " written back as WGS 84";
}

void SurveyWriter::write_comment(double time) {
  writer_->write(Comment{time, comment_});
  commented_ = true;
}

void SurveyWriter::ping(double time, std::span<const Beam> beams) {
  if (!commented_) write_comment(time);
  const std::optional<NavSample> at = interpolate_nav(nav_, time);
  if (!at) return;
  // The ping header's fields are coarse (1e-7 deg of position, 0.01 deg, 1 cm of vehicle depth),
  // the beam arrays fine (0.1 mm). Each beam is written relative to the ping as stored, its
  // rounding included, so that reading back puts every sounding where it was to the arrays'
  // resolution, not off by range times an angle's rounding or by a position's: the angles'
  // rounding is taken out in the rotation into the level frame, the position's and the vehicle
  // depth's in the offsets.
  auto centi = [](double deg) { return std::round(deg * 100.0) / 100.0; };
  Ping p;
  p.time = time;
  const auto ll = projection_->inverse(at->easting, at->northing);
  p.longitude_deg = std::round(ll.longitude_deg * 1e7) / 1e7;  // the field's resolution
  p.latitude_deg = std::round(ll.latitude_deg * 1e7) / 1e7;
  p.heading_deg = heading_field(at->heading_deg) / 100.0;
  p.course_deg = p.heading_deg;
  p.pitch_deg = centi(at->pitch_deg);
  p.roll_deg = centi(at->roll_deg);
  p.depth_corrector_m = centi(at->depth_m);
  std::uint32_t n = 0;
  for (const Beam& b : beams) n = std::max(n, b.index + 1);
  p.num_beams = static_cast<int>(n);
  p.center_beam = p.num_beams / 2;
  p.depth_m.assign(n, 0.0);
  p.across_m.assign(n, 0.0);
  p.along_m.assign(n, 0.0);
  p.beam_flags.assign(n, 1);  // beams the survey does not have are marked unusable
  const Eigen::Matrix3d vehicle_to_level = yaw(p.heading_deg).transpose() * yaw(at->heading_deg) *
                                           tilt(at->roll_deg, at->pitch_deg);
  // From the stored position to the true one (north, east, down), in the level frame.
  const auto stored = projection_->forward(p.longitude_deg, p.latitude_deg);
  const Eigen::Vector3d position_rounding =
      yaw(p.heading_deg).transpose() * Eigen::Vector3d(at->northing - stored.northing, at->easting - stored.easting, 0);
  for (const Beam& b : beams) {
    const Eigen::Vector3d level = vehicle_to_level * Eigen::Vector3d(b.along, b.across, b.down) + position_rounding;
    p.along_m[b.index] = level.x();
    p.across_m[b.index] = level.y();
    p.depth_m[b.index] = level.z() + at->depth_m;  // the sounding's depth, not the rounded corrector's
    p.beam_flags[b.index] = 0;
  }
  writer_->write(p);
}

std::uint64_t SurveyWriter::close() {
  if (!commented_) write_comment(0.0);
  writer_->close();
  return writer_->pings_written();
}

std::uint64_t write_survey(const Survey& survey, const std::vector<NavSample>& nav, const std::filesystem::path& path) {
  SurveyWriter writer(path, nav);
  writer.begin(survey);
  for (const bathyslam::Ping& ping : survey.pings) writer.ping(ping.time, survey.beams_of(ping));
  return writer.close();
}

std::optional<double> first_ping_time(const std::filesystem::path& path) {
  FileSource source(path);
  Reader reader(source, path.string());
  while (const auto record = reader.next()) {
    if (const auto* ping = std::get_if<Ping>(&*record)) return ping->time;
  }
  return std::nullopt;
}

bool is_gsf_path(const std::filesystem::path& path) {
  return has_extension(path, ".gsf");
}

}  // namespace bathyslam::gsf
