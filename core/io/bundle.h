#pragma once
// The survey bundle (docs/design.md, "Survey bundle"): a folder, or a .tar of one, with survey.json,
// nav.csv, pings.csv and optionally reference_nav.csv. Reading validates everything and yields a Survey
// only when there is no error; every problem names its file, line and field.
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "core/io/bounded_json.h"
#include "core/io/byte_source.h"
#include "core/io/problem.h"
#include "core/types/survey.h"

namespace bathyslam {

inline constexpr std::string_view kSurveyJsonFile = "survey.json";
inline constexpr std::string_view kNavFile = "nav.csv";
inline constexpr std::string_view kPingsFile = "pings.csv";
inline constexpr std::string_view kReferenceNavFile = "reference_nav.csv";

// survey.json describes the survey; its free-form "sonar" and "vehicle" need neither megabytes
// nor deep nesting.
inline constexpr JsonLimits kSurveyJsonLimits{.max_bytes = 1 << 20, .max_depth = 64};

inline constexpr std::string_view kNavHeader = "time,easting,northing,depth,roll,pitch,heading";
inline constexpr std::string_view kPingsHeader = "time,beam,along,across,down";

// --- parsers of single files (`file` names the file in problems) -------------------------------

SurveyMetadata parse_survey_json(std::string_view text, std::string_view file,
                                 ProblemList& problems);

std::vector<NavSample> parse_nav_csv(ByteSource& source, std::string_view file,
                                     ProblemList& problems);

// A reference navigation given beside sonar files (`--reference-nav`): a nav.csv-format file.
// Throws std::runtime_error listing its problems.
std::vector<NavSample> read_reference_nav(const std::filesystem::path& path);

struct TimeSpan {
  double begin = 0;
  double end = 0;
};

class PingSink;

// Hands each ping of `source` to `sink.ping` in file order, its beams as far as they parsed. With
// `nav_span`, pings outside it are reported as one warning (the sync stage drops them).
void stream_pings_csv(ByteSource& source, std::string_view file, const std::optional<TimeSpan>& nav_span,
                      ProblemList& problems, PingSink& sink);

// stream_pings_csv appending the pings and beams to `pings`/`beams`.
void parse_pings_csv(ByteSource& source, std::string_view file,
                     const std::optional<TimeSpan>& nav_span, ProblemList& problems,
                     std::vector<Ping>& pings, std::vector<Beam>& beams);

// --- the whole bundle ---------------------------------------------------------------------------

struct BundleReadResult {
  std::optional<Survey> survey;  // set only when there is no error
  std::vector<Problem> problems;  // errors and warnings, in file order
};

BundleReadResult read_bundle(const std::filesystem::path& bundle);  // a folder or a tar

// Where stream_bundle hands the pings: a survey's soundings are most of its memory (`large`:
// 2.6 GB), so a reader that only turns them into something else need not hold them all.
class PingSink {
 public:
  virtual ~PingSink() = default;
  // Before the first ping: the survey read so far, its metadata, navigation and reference
  // navigation (possibly with errors already: the pings are read on to report theirs).
  virtual void begin(const Survey& survey) = 0;
  // A ping's time and its beams, valid during the call only.
  virtual void ping(double time, std::span<const Beam> beams) = 0;
};

// read_bundle handing the pings to `sink` as they are read: the survey comes back without pings
// and beams. A bundle with errors comes back without a survey as from read_bundle, but the sink
// has seen pings by then: the caller discards what it made of them.
BundleReadResult stream_bundle(const std::filesystem::path& bundle, PingSink& sink);
class BundleSource;
// The same from files kept elsewhere (core/io/bundle_files.h).
BundleReadResult stream_bundle(const BundleSource& bundle, PingSink& sink);

class BundleError : public std::runtime_error {
 public:
  explicit BundleError(std::vector<Problem> problems);
  const std::vector<Problem>& problems() const { return problems_; }

 private:
  std::vector<Problem> problems_;
};

// read_bundle for callers that want the survey or an exception listing every error.
Survey load_bundle(const std::filesystem::path& bundle);

// Writes `survey` as a bundle into `dir` (created if needed). Each file is written under a
// temporary name and renamed, so a reader never sees half a file. Numbers are written in their
// shortest exact form: reading the bundle back gives the same values.
void write_bundle(const Survey& survey, const std::filesystem::path& dir);

// The same but pings.csv, which a PingsCsvWriter writes ping by ping (a survey too large to
// hold: `bathyslam simulate` streams its pings). survey.json comes last: with it, the bundle is
// whole.
void write_bundle_without_pings(const Survey& survey, const std::filesystem::path& dir);

namespace detail {
class AtomicFileWriter;
}

// pings.csv written as the pings come, atomically: under a temporary name until commit().
class PingsCsvWriter {
 public:
  explicit PingsCsvWriter(const std::filesystem::path& path);
  ~PingsCsvWriter();  // without commit(): the temporary file is removed
  PingsCsvWriter(const PingsCsvWriter&) = delete;
  PingsCsvWriter& operator=(const PingsCsvWriter&) = delete;
  void add(double time, std::span<const Beam> beams);
  void commit();

 private:
  std::unique_ptr<detail::AtomicFileWriter> out_;
};

// Writes navigation in the nav.csv format (header and columns), atomically.
void write_nav_csv(const std::vector<NavSample>& nav, const std::filesystem::path& path);

}  // namespace bathyslam
