#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <cstring>
#include <functional>
#include <future>
#include <limits>
#include <string>

#include "core/io/bundle.h"

#include "core/io/bounded_json.h"
#include "core/io/bundle_files.h"
#include "core/io/crs.h"
#include "core/io/csv.h"

namespace bathyslam {
namespace {

// Line (1-based) of the first occurrence of "key" in a JSON text, so a problem with a field of
// survey.json can point at it; 1 when the key does not appear.
std::size_t line_of_key(std::string_view text, std::string_view key) {
  const std::string needle = "\"" + std::string(key) + "\"";
  const std::size_t at = text.find(needle);
  if (at == std::string_view::npos) return 1;
  return 1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + at, '\n'));
}

std::size_t line_of_byte(std::string_view text, std::size_t byte) {
  byte = std::min(byte, text.size());
  return 1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + byte, '\n'));
}

// Checks the header line; false (with a problem) when it is missing or not exactly `expected`.
bool check_header(LineReader& lines, std::string_view file, std::string_view expected,
                  ProblemList& problems) {
  std::string_view header;
  if (!lines.next(header)) {
    problems.error(std::string(file), 1, "", "empty file; expected the header '" +
                                                 std::string(expected) + "'");
    return false;
  }
  if (header.size() >= 3 && std::memcmp(header.data(), "\xEF\xBB\xBF", 3) == 0) {
    header.remove_prefix(3);  // a byte-order mark left by spreadsheet tools
  }
  if (header != expected) {
    problems.error(std::string(file), 1, "",
                   "header is " + quoted_input(header) + "; expected exactly '" +
                       std::string(expected) + "'");
    return false;
  }
  return true;
}

// Parses fields[i] into `value`, reporting a problem naming the column when it fails.
template <typename T>
bool parse_field(std::string_view text, T& value, std::string_view file, std::size_t line,
                 std::string_view column, ProblemList& problems) {
  const NumberError error = parse_number(text, value);
  if (error == NumberError::kNone) return true;
  problems.error(std::string(file), line, std::string(column),
                 std::string(describe(error)) + ": " + quoted_input(text));
  return false;
}

// No projected coordinate in metres lies this far from its CRS's origin: the Earth's circumference
// is 4.0e7 m, false eastings and northings a few 1e6 m.
constexpr double kMaxProjectedCoordinate_m = 1e8;
// Deeper than the deepest ocean (10.9 km), or higher than any vehicle with a multibeam flies.
constexpr double kMaxVehicleDepth_m = 12000;
// Soundings of one ping: what GSF's 2-byte beam count holds (the corrected GSF of every job), and
// tens of times what any multibeam forms (an EM2040 dual swath: 1,600).
constexpr std::size_t kMaxBeamsPerPing = 65535;

bool check_field_count(std::size_t count, std::size_t expected, std::string_view file,
                       std::size_t line, ProblemList& problems) {
  if (count == expected) return true;
  problems.error(std::string(file), line, "",
                 std::to_string(count) + " fields; expected " + std::to_string(expected));
  return false;
}

}  // namespace

SurveyMetadata parse_survey_json(std::string_view text, std::string_view file,
                                 ProblemList& problems) {
  const std::string name(file);
  SurveyMetadata metadata;
  nlohmann::json doc;
  try {
    doc = parse_bounded_json(text, kSurveyJsonLimits);
  } catch (const nlohmann::json::parse_error& e) {
    problems.error(name, line_of_byte(text, e.byte), "", std::string("not valid JSON: ") + e.what());
    return metadata;
  } catch (const JsonLimitError& e) {
    problems.error(name, 0, "", e.what());
    return metadata;
  }
  if (!doc.is_object()) {
    problems.error(name, 1, "", "expected a JSON object");
    return metadata;
  }
  auto string_field = [&](std::string_view key, std::string& out) {
    const auto it = doc.find(key);
    if (it == doc.end()) {
      problems.error(name, 1, std::string(key), "missing");
    } else if (!it->is_string() || it->get_ref<const std::string&>().empty()) {
      problems.error(name, line_of_key(text, key), std::string(key),
                     "must be a non-empty string");
    } else {
      out = it->get<std::string>();
      return true;
    }
    return false;
  };
  auto object_field = [&](std::string_view key, nlohmann::json& out) {
    const auto it = doc.find(key);
    if (it == doc.end()) return;  // optional
    if (!it->is_object()) {
      problems.error(name, line_of_key(text, key), std::string(key), "must be a JSON object");
      return;
    }
    out = *it;
  };
  string_field("name", metadata.name);
  if (string_field("crs", metadata.crs)) {
    if (auto why = crs_problem(metadata.crs)) {
      problems.error(name, line_of_key(text, "crs"), "crs", *why);
    }
  }
  object_field("sonar", metadata.sonar);
  object_field("vehicle", metadata.vehicle);
  return metadata;
}

std::vector<NavSample> read_reference_nav(const std::filesystem::path& path) {
  FileSource source(path);
  ProblemList problems;
  std::vector<NavSample> reference = parse_nav_csv(source, path.string(), problems);
  if (problems.has_errors()) {
    std::string why = "reference navigation is not in the nav.csv format:";
    for (const Problem& p : problems.take()) why += "\n  " + p.to_string();
    throw std::runtime_error(why);
  }
  return reference;
}

std::vector<NavSample> parse_nav_csv(ByteSource& source, std::string_view file,
                                     ProblemList& problems) {
  static constexpr std::array<std::string_view, 7> kColumns = {
      "time", "easting", "northing", "depth", "roll", "pitch", "heading"};
  std::vector<NavSample> nav;
  const std::size_t errors_before = problems.error_count();
  LineReader lines(source);
  if (!check_header(lines, file, kNavHeader, problems)) return nav;

  std::array<std::string_view, 7> fields;
  std::string_view line;
  double previous_time = -std::numeric_limits<double>::infinity();
  while (lines.next(line)) {
    const std::size_t n = lines.line_number();
    if (line.empty()) continue;
    if (!check_field_count(split_fields(line, fields), fields.size(), file, n, problems)) continue;
    NavSample s;
    double* values[] = {&s.time,     &s.easting,   &s.northing,   &s.depth_m,
                        &s.roll_deg, &s.pitch_deg, &s.heading_deg};
    bool ok = true;
    for (std::size_t i = 0; i < fields.size(); ++i) {
      ok &= parse_field(fields[i], *values[i], file, n, kColumns[i], problems);
    }
    if (!ok) continue;
    if (s.time < previous_time) {
      problems.error(std::string(file), n, "time",
                     "goes backwards: " + std::string(fields[0]) + " after " +
                         std::to_string(previous_time));
    }
    // Positions and depths no survey can have reach the map as infinite longitudes and cell counts.
    for (const std::size_t i : {1, 2}) {  // easting, northing
      if (std::abs(*values[i]) > kMaxProjectedCoordinate_m) {
        problems.error(std::string(file), n, std::string(kColumns[i]),
                       quoted_input(fields[i]) + " m is no projected coordinate (beyond ±1e8 m)");
      }
    }
    if (std::abs(s.depth_m) > kMaxVehicleDepth_m) {
      problems.error(std::string(file), n, "depth", quoted_input(fields[3]) + " m is beyond ±12000 m");
    }
    if (std::abs(s.roll_deg) > 90) problems.error(std::string(file), n, "roll", "outside ±90°");
    if (std::abs(s.pitch_deg) > 90) problems.error(std::string(file), n, "pitch", "outside ±90°");
    previous_time = std::max(previous_time, s.time);
    nav.push_back(s);
  }
  if (nav.size() < 2 && problems.error_count() == errors_before) {
    problems.error(std::string(file), 0, "", "needs at least 2 navigation samples, has " +
                                                 std::to_string(nav.size()));
  }
  return nav;
}

void stream_pings_csv(ByteSource& source, std::string_view file, const std::optional<TimeSpan>& nav_span,
                      ProblemList& problems, PingSink& sink) {
  static constexpr std::array<std::string_view, 5> kColumns = {"time", "beam", "along", "across",
                                                               "down"};
  const std::size_t errors_before = problems.error_count();
  LineReader lines(source);
  if (!check_header(lines, file, kPingsHeader, problems)) return;

  std::array<std::string_view, 5> fields;
  std::string_view line;
  // Rows of one ping repeat its time text; comparing text is cheaper than parsing it again.
  std::string time_text;
  double time = -std::numeric_limits<double>::infinity();
  bool in_ping = false;
  std::vector<Beam> ping_beams;  // the ping being read: handed on when the next one starts
  std::size_t pings = 0, soundings = 0;
  std::size_t outside_pings = 0, first_outside_line = 0;

  while (lines.next(line)) {
    const std::size_t n = lines.line_number();
    if (line.empty()) continue;
    if (!check_field_count(split_fields(line, fields), fields.size(), file, n, problems)) continue;

    if (!in_ping || fields[0] != time_text) {
      double t = 0;
      if (!parse_field(fields[0], t, file, n, kColumns[0], problems)) continue;
      if (t < time) {
        problems.error(std::string(file), n, "time",
                       "goes backwards: " + std::string(fields[0]) + " after " + time_text);
        continue;
      }
      time_text.assign(fields[0]);
      if (!in_ping || t != time) {
        if (in_ping) sink.ping(time, ping_beams);
        ping_beams.clear();
        time = t;
        in_ping = true;
        ++pings;
        if (nav_span && (t < nav_span->begin || t > nav_span->end) && outside_pings++ == 0) {
          first_outside_line = n;
        }
      }
    }

    Beam beam;
    bool ok = parse_field(fields[1], beam.index, file, n, kColumns[1], problems);
    ok &= parse_field(fields[2], beam.along, file, n, kColumns[2], problems);
    ok &= parse_field(fields[3], beam.across, file, n, kColumns[3], problems);
    ok &= parse_field(fields[4], beam.down, file, n, kColumns[4], problems);
    if (!ok) continue;
    if (!ping_beams.empty() && beam.index <= ping_beams.back().index) {
      problems.error(std::string(file), n, "beam",
                     "beam " + std::to_string(beam.index) + " follows beam " +
                         std::to_string(ping_beams.back().index) +
                         " in the same ping; beams must increase within a ping");
      continue;
    }
    if (ping_beams.size() >= kMaxBeamsPerPing) {
      if (ping_beams.size() == kMaxBeamsPerPing) {  // said once per ping, at its first beam too many
        problems.error(std::string(file), n, "beam",
                       "the ping at time " + time_text + " has more than " + std::to_string(kMaxBeamsPerPing) +
                           " beams (a GSF ping's limit; no multibeam forms that many)");
        ping_beams.push_back(beam);
      }
      continue;
    }
    if (soundings >= std::numeric_limits<uint32_t>::max()) {
      problems.error(std::string(file), n, "", "more than 2^32 soundings");
      return;
    }
    ping_beams.push_back(beam);
    ++soundings;
  }
  if (in_ping) sink.ping(time, ping_beams);
  if (pings == 0 && problems.error_count() == errors_before) {
    problems.error(std::string(file), 0, "", "no pings");
  }
  if (outside_pings > 0) {
    problems.warning(std::string(file), first_outside_line, "time",
                     std::to_string(outside_pings) +
                         " pings lie outside the navigation's time span [" +
                         std::to_string(nav_span->begin) + ", " + std::to_string(nav_span->end) +
                         "] and will be dropped (first here)");
  }
}

namespace {

// The pings and beams appended to a survey's vectors.
class SurveyPings : public PingSink {
 public:
  SurveyPings(std::vector<Ping>& pings, std::vector<Beam>& beams) : pings_(pings), beams_(beams) {}
  void begin(const Survey&) override {}
  void ping(double time, std::span<const Beam> beams) override {
    pings_.push_back({time, static_cast<uint32_t>(beams_.size()), static_cast<uint32_t>(beams.size())});
    beams_.insert(beams_.end(), beams.begin(), beams.end());
  }

 private:
  std::vector<Ping>& pings_;
  std::vector<Beam>& beams_;
};

}  // namespace

void parse_pings_csv(ByteSource& source, std::string_view file, const std::optional<TimeSpan>& nav_span,
                     ProblemList& problems, std::vector<Ping>& pings, std::vector<Beam>& beams) {
  SurveyPings sink(pings, beams);
  stream_pings_csv(source, file, nav_span, problems, sink);
}

BundleReadResult stream_bundle(const std::filesystem::path& bundle, PingSink& sink) {
  std::optional<BundleFiles> files;
  try {
    files.emplace(bundle);
  } catch (const std::exception& e) {
    BundleReadResult result;
    result.problems.push_back({Problem::Severity::kError, "", 0, "", e.what()});  // the bundle itself; the message names it
    return result;
  }
  return stream_bundle(*files, sink);
}

BundleReadResult stream_bundle(const BundleSource& bundle, PingSink& sink) {
  ProblemList problems;
  Survey survey;
  auto open_into = [&](ProblemList& said, std::string_view file, bool required) -> std::unique_ptr<ByteSource> {
    if (!bundle.contains(file)) {
      if (required) said.error(std::string(file), 0, "", "missing from " + bundle.name());
      return nullptr;
    }
    try {
      return bundle.open(file);
    } catch (const std::exception& e) {
      said.error(std::string(file), 0, "", e.what());
      return nullptr;
    }
  };
  auto open = [&](std::string_view file, bool required) { return open_into(problems, file, required); };

  if (auto json = open(kSurveyJsonFile, true)) {
    survey.metadata = parse_survey_json(read_at_most(*json, kSurveyJsonLimits.max_bytes), kSurveyJsonFile, problems);
  }
  // A line too long ends the reading of its file with a problem at that line.
  auto guarded_into = [&](ProblemList& said, std::string_view file, const std::function<void()>& parse) {
    try {
      parse();
    } catch (const LineTooLong& e) {
      said.error(std::string(file), e.line(), "", e.what());
    }
  };
  auto guarded = [&](std::string_view file, const std::function<void()>& parse) { guarded_into(problems, file, parse); };
  // The reference navigation is read on a thread of its own beside the navigation: a deep-water
  // survey logs each at 20 Hz for a day, more text than its soundings (docs/any-depth.md). Its
  // problems follow the navigation's, as when read after it.
  ProblemList reference_problems;
  const bool has_reference = bundle.contains(kReferenceNavFile);
  std::future<void> reading_reference = std::async(has_reference ? std::launch::async : std::launch::deferred, [&] {
    if (auto reference = open_into(reference_problems, kReferenceNavFile, false)) {
      guarded_into(reference_problems, kReferenceNavFile,
                   [&] { survey.reference_nav = parse_nav_csv(*reference, kReferenceNavFile, reference_problems); });
    }
  });
  std::optional<TimeSpan> nav_span;
  if (auto nav = open(kNavFile, true)) {
    guarded(kNavFile, [&] { survey.nav = parse_nav_csv(*nav, kNavFile, problems); });
    if (survey.nav.size() >= 2) nav_span = TimeSpan{survey.nav.front().time, survey.nav.back().time};
  }
  reading_reference.get();
  problems.append(std::move(reference_problems));
  if (auto pings = open(kPingsFile, true)) {
    sink.begin(survey);
    guarded(kPingsFile, [&] { stream_pings_csv(*pings, kPingsFile, nav_span, problems, sink); });
  }

  BundleReadResult result;
  if (!problems.has_errors()) result.survey = std::move(survey);
  result.problems = problems.take();
  return result;
}

BundleReadResult read_bundle(const std::filesystem::path& bundle) {
  std::vector<Ping> pings;
  std::vector<Beam> beams;
  SurveyPings sink(pings, beams);
  BundleReadResult result = stream_bundle(bundle, sink);
  if (result.survey) {
    result.survey->pings = std::move(pings);
    result.survey->beams = std::move(beams);
  }
  return result;
}

namespace {
std::string describe_errors(const std::vector<Problem>& problems) {
  std::string text = "invalid survey bundle:";
  for (const Problem& p : problems) {
    if (p.severity == Problem::Severity::kError) text += "\n  " + p.to_string();
  }
  return text;
}
}  // namespace

BundleError::BundleError(std::vector<Problem> problems)
    : std::runtime_error(describe_errors(problems)), problems_(std::move(problems)) {}

Survey load_bundle(const std::filesystem::path& bundle) {
  BundleReadResult result = read_bundle(bundle);
  if (!result.survey) throw BundleError(std::move(result.problems));
  return std::move(*result.survey);
}

}  // namespace bathyslam
