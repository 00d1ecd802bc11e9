#pragma once
// The registrations of a report.json, read back as the benchmarks need them to rebuild edges.
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "core/graph/pose_graph.h"
#include "core/pipeline/pipeline.h"

namespace bathyslam::bench {

struct ReportRegistration {
  int from = 0, to = 0;
  std::string type;  // "adjacent" or "loop"
  std::string path;  // "direct", "feature-aided" or empty (`gicp`)
  bool accepted = false;
  bool has_measured = false;  // reports written before the measured pose was kept lack it
  Eigen::Isometry3d measured = Eigen::Isometry3d::Identity();
  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();
  Information6 information = Information6::Zero();  // accepted ones only
};

struct Report {
  std::vector<ReportRegistration> registrations;
  // The run's parameters, for re-solving under the same graph settings.
  PipelineConfig config;
};

// Throws std::runtime_error naming the file and the entry when it cannot be read, is not a
// report, or names submaps outside [0, submaps).
Report read_report(const std::string& path, int submaps);

}  // namespace bathyslam::bench
