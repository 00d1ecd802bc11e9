#pragma once
// The quality report of a pipeline run: JSON for machines, a few lines for people, PNG plots.
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "core/pipeline/pipeline.h"

namespace bathyslam {

// Candidates, accepted (in the graph) and rejected, with the rejections counted by kind.
struct ConstraintCounts {
  std::int64_t candidates = 0, accepted = 0, rejected = 0;
  std::map<std::string, std::int64_t> rejections;  // by to_string(RejectionKind)
};

// The report's headline numbers, typed: what the service stores inside report.json and reads
// back (report_summary_from_json) to answer GetReport.
struct ReportSummary {
  std::string configuration;
  ErrorStats trajectory, trajectory_dr;    // against the reference, unaligned
  ErrorStats consistency, consistency_dr;
  Histogram histogram;                     // consistency error of the published map
  std::map<std::string, ConstraintCounts> by_type;  // odometry, adjacent, loop
  std::map<std::string, ConstraintCounts> by_path;  // direct, feature-aided
};

ReportSummary report_summary(const PipelineResult& result);

// Why a figure could not be computed, or nullopt when it was: its statistics are then null in
// report.json and the text says so, rather than a zero a reader would take for a perfect result.
std::optional<std::string> trajectory_not_computed(const PipelineResult& result);   // no reference navigation
std::optional<std::string> consistency_not_computed(const PipelineResult& result);  // no overlap between lines
// Throws std::runtime_error naming the first key it misses: a report is read exactly, never as
// zeros.
ReportSummary report_summary_from_json(const nlohmann::json& report);

// Everything: the summary's numbers under their keys, the parameters, every registration, the
// safety net, the timings.
nlohmann::json report_json(const PipelineResult& result);
// A few lines for people.
std::string report_text(const PipelineResult& result);
// consistency_histogram.png, trajectory_error.png, trajectory.png into `dir`.
void write_report_plots(const PipelineResult& result, const std::filesystem::path& dir);

}  // namespace bathyslam
