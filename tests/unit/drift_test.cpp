#include "core/sim/drift.h"

#include <gtest/gtest.h>

#include "core/lines/survey_lines.h"
#include "core/sim/trajectory.h"

namespace bathyslam::sim {
namespace {

std::vector<NavSample> truth_of(Scenario scenario, double every_s) {
  const auto stride = static_cast<std::size_t>(std::lround(every_s / MotionConfig{}.step_s));
  return navigation_of(drive(survey_pattern(scenario), MotionConfig{}), stride);
}

std::vector<NavSample> lake_truth(double every_s) { return truth_of(Scenario::kLake, every_s); }

double mean_rms_error(const std::vector<NavSample>& truth, const DvlDrift& drift, int seeds) {
  double sum = 0;
  for (int seed = 1; seed <= seeds; ++seed) sum += drift_stats(apply_dvl_drift(truth, drift, seed), truth).rms_m;
  return sum / seeds;
}

// Heading error of dead reckoning against the truth, in degrees within (-180, 180].
double heading_error_deg(const NavSample& dr, const NavSample& truth) {
  return std::remainder(dr.heading_deg - truth.heading_deg, 360.0);
}

TEST(PaperDrift, MeanDrErrorOverLakeMatchesThePaper) {
  const auto truth = lake_truth(0.5);
  // Seeds other than the calibration's: the magnitude is a property of the model, not a fit.
  double sum = 0;
  constexpr int kSeeds = 40;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    sum += drift_stats(apply_paper_drift(truth, truth.front().time, PaperDrift{}, seed), truth).mean_m;
  }
  const double mean = sum / kSeeds;
  EXPECT_NEAR(mean, kPaperMeanDrError_m, 0.25 * kPaperMeanDrError_m);
  const double sigma = calibrated_paper_sigma_yaw();
  EXPECT_GT(sigma, 1e-5);
  EXPECT_LT(sigma, 1e-2) << "taken literally, 0.01 rad drifts hundreds of metres (docs/design.md)";
}

TEST(PaperDrift, FirstPoseSharedAndRollPitchUntouched) {
  const auto truth = lake_truth(0.5);
  const auto dr = apply_paper_drift(truth, truth.front().time, PaperDrift{}, 3);
  EXPECT_EQ(dr.front().easting, truth.front().easting);
  EXPECT_EQ(dr.front().northing, truth.front().northing);
  for (std::size_t i = 0; i < dr.size(); i += 97) {
    EXPECT_EQ(dr[i].roll_deg, truth[i].roll_deg);
    EXPECT_EQ(dr[i].pitch_deg, truth[i].pitch_deg);
  }
  EXPECT_GT(drift_stats(dr, truth).max_m, 1.0);
}

TEST(DvlDrift, DriftsAboutPointThreePercentOfDistanceAlongALine) {
  const auto truth = lake_truth(0.05);
  const std::vector<SurveyLine> lines = split_lines(truth);
  ASSERT_GE(lines.size(), 7u);
  const SurveyLine& first = lines.front();
  ASSERT_GT(first.length_m, 700.0);
  // Error gained along the first survey line, relative to its length, averaged over seeds.
  double sum = 0;
  constexpr int kSeeds = 60;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    const auto dr = apply_dvl_drift(truth, DvlDrift{}, seed);
    auto error = [&](std::size_t i) {
      return Eigen::Vector2d(dr[i].easting - truth[i].easting, dr[i].northing - truth[i].northing);
    };
    sum += (error(first.last) - error(first.first)).norm() / first.length_m;
  }
  EXPECT_NEAR(sum / kSeeds, 0.003, 0.001);
}

TEST(HeadingWalkDrift, DriftsFarMoreThanDvlOnASmallSurvey) {
  const auto truth = truth_of(Scenario::kSmall, 0.05);
  const double dvl = mean_rms_error(truth, DvlDrift{}, 8);
  const double walk = mean_rms_error(truth, make_heading_walk_drift(), 8);
  EXPECT_GT(walk, 4.0 * dvl) << "dvl " << dvl << " m, heading-walk " << walk << " m";
}

TEST(HeadingWalkDrift, TensOfMetresOverLake) {
  const double rms = mean_rms_error(lake_truth(0.5), make_heading_walk_drift(), 16);
  EXPECT_GT(rms, 15.0);
  EXPECT_LT(rms, 40.0);
}

TEST(CompassStepDrift, HeadingErrorJumpsOnceByTheDrawnStep) {
  const auto truth = truth_of(Scenario::kSmall, 0.05);
  const CompassStepDrift drift;
  const double span = truth.back().time - truth.front().time;
  bool positive = false, negative = false;
  for (uint64_t seed = 1; seed <= 8; ++seed) {
    const HeadingStep step = draw_compass_step(truth, drift, seed);
    const double step_deg = step.step_rad * 180.0 / M_PI;
    EXPECT_GE(std::abs(step_deg), drift.min_step_deg);
    EXPECT_LE(std::abs(step_deg), drift.max_step_deg);
    EXPECT_GE(step.time, truth.front().time + 0.25 * span);
    EXPECT_LE(step.time, truth.front().time + 0.75 * span);
    (step_deg > 0 ? positive : negative) = true;

    const auto dr = apply_dvl_drift(truth, drift.dvl, seed, step);
    const auto dvl = apply_dvl_drift(truth, drift.dvl, seed);
    std::size_t jump = 0;
    double largest = 0;
    for (std::size_t i = 1; i < dr.size(); ++i) {
      const double change = heading_error_deg(dr[i], truth[i]) - heading_error_deg(dr[i - 1], truth[i - 1]);
      if (std::abs(change) > std::abs(largest)) {
        largest = change;
        jump = i;
      }
    }
    EXPECT_NEAR(largest, step_deg, 0.01) << "seed " << seed;
    EXPECT_GE(dr[jump].time, step.time);
    EXPECT_LT(dr[jump - 1].time, step.time);
    // Before the fault the track is dvl's; after it, the track turns away.
    EXPECT_EQ(dr[jump - 1].easting, dvl[jump - 1].easting);
    EXPECT_GT(drift_stats(dr, truth).end_m, drift_stats(dvl, truth).end_m) << "seed " << seed;
  }
  EXPECT_TRUE(positive && negative) << "the step's sign is drawn";
}

}  // namespace
}  // namespace bathyslam::sim
