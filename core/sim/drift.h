#pragma once
// Dead reckoning that drifts away from the true navigation (docs/design.md, "Drift, two models").
#include <cstdint>
#include <optional>
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

// dvl's sensors but a heading bias that wanders by degrees over a survey, as a poorly aided gyro
// does: tens of metres of DR error on `lake` (docs/simulator.md), beyond what registration corrects from a
// dead-reckoning guess.
DvlDrift make_heading_walk_drift();

// dvl with a compass fault: at one moment in the middle half of the survey the heading reading
// jumps by a few degrees and stays off, so the dead-reckoned track turns about that point.
struct CompassStepDrift {
  DvlDrift dvl;
  double min_step_deg = 3.0;
  double max_step_deg = 8.0;
  // The fault's time, as fractions of the navigation's span: survey on both sides of it.
  double earliest = 0.25;
  double latest = 0.75;
};

// A jump of the heading error from `time` on (its sign random).
struct HeadingStep {
  double time = 0;
  double step_rad = 0;
};

// The fault of a compass-step survey, drawn from the seed: the same for the same seed.
HeadingStep draw_compass_step(const std::vector<NavSample>& truth, const CompassStepDrift& drift,
                              uint64_t seed);

// The mean DR error (over poses, averaged over seeds) that the paper reports for its survey.
inline constexpr double kPaperMeanDrError_m = 17.53;

// The paper model's sigma_yaw that gives a mean DR error of kPaperMeanDrError_m over the
// `lake` scenario (Monte Carlo over fixed seeds; computed once per process).
double calibrated_paper_sigma_yaw();

// `truth` must be time-ordered. `key_time` is the start of the first submap: nav before it
// keeps the true pose.
std::vector<NavSample> apply_paper_drift(const std::vector<NavSample>& truth, double key_time,
                                         const PaperDrift& drift, uint64_t seed);

// With `step`, the heading error jumps at its time; the drift before it is dvl's for the seed.
std::vector<NavSample> apply_dvl_drift(const std::vector<NavSample>& truth, const DvlDrift& drift,
                                       uint64_t seed,
                                       std::optional<HeadingStep> step = std::nullopt);

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
