#pragma once
// Dead reckoning that drifts away from the true navigation (design.md, "Drift, two models").
#include <cstdint>
#include <vector>

#include "core/types/survey.h"

namespace bathyslam::sim {

// The paper's model: zero-mean Gaussian noise on each relative pose between consecutive submaps
// (x, y, z and yaw; roll and pitch untouched), accumulated from the first pose, which is shared.
struct PaperDrift {
  double sigma_translation_m = 0.01;
  double sigma_yaw_rad = 0.0;  // 0: calibrated_paper_sigma_yaw()
  double submap_duration_s = 10.0;  // 100 pings at 10 pings/s
};

// A DVL-aided INS: velocity scale error, a heading bias that starts random and drifts as a
// random walk, and white velocity noise. The defaults drift about 0.3 % of distance travelled
// along a straight line (E|(scale, bias)| = 0.3 %).
struct DvlDrift {
  double scale_sigma = 0.0024;
  double heading_bias_sigma_rad = 0.0024;
  double heading_bias_walk_rad_per_sqrt_s = 2e-5;
  double velocity_noise_m_s = 0.01;
};

// The mean DR error (over poses, averaged over seeds) that the paper reports for its survey.
inline constexpr double kPaperMeanDrError_m = 17.53;

// The paper model's sigma_yaw that gives a mean DR error of kPaperMeanDrError_m over the
// `lake` scenario (Monte Carlo over fixed seeds; computed once per process).
double calibrated_paper_sigma_yaw();

// `truth` must be time-ordered. `key_time` is the start of the first submap: nav before it
// keeps the true pose.
std::vector<NavSample> apply_paper_drift(const std::vector<NavSample>& truth, double key_time,
                                         const PaperDrift& drift, uint64_t seed);

std::vector<NavSample> apply_dvl_drift(const std::vector<NavSample>& truth, const DvlDrift& drift,
                                       uint64_t seed);

// Horizontal position error of `nav` against `reference`, sample by sample (same times).
struct DriftStats {
  double mean_m = 0;
  double rms_m = 0;
  double max_m = 0;
  double end_m = 0;
  double distance_travelled_m = 0;
};
DriftStats drift_stats(const std::vector<NavSample>& nav, const std::vector<NavSample>& reference);

}  // namespace bathyslam::sim
