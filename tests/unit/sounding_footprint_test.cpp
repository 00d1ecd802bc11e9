// The sounding footprint and the lengths that follow it: measured from a survey's pings, the
// power-of-two scale of Table 1's lengths, and which parameters scale (lengths, areas) and which
// do not (counts, ratios, navigation noise, a value the user set).
#include "core/submaps/sounding_footprint.h"

#include <gtest/gtest.h>

#include "core/pipeline/parameters.h"
#include "core/submaps/submap.h"

namespace bathyslam {
namespace {

// Sailing east at 1 m per ping, 101 beams across `swath` metres, 10 m below the sonar but for one
// stray beam each ping.
Survey straight_survey(int pings, double swath) {
  Survey survey;
  for (int i = 0; i <= pings; ++i) survey.nav.push_back({.time = double(i), .easting = double(i), .heading_deg = 90});
  for (int i = 0; i < pings; ++i) {
    survey.pings.push_back({double(i) + 0.5, static_cast<uint32_t>(survey.beams.size()), 101});
    for (int b = 0; b <= 100; ++b) {
      survey.beams.push_back({static_cast<uint32_t>(b), 0, static_cast<float>(swath * (b / 100.0 - 0.5)), b == 7 ? 500.0f : 10.0f});
    }
  }
  return survey;
}

TEST(SoundingFootprint, IsTheAreaPerSoundingAndTheMedianHeight) {
  const SubmapSet set = build_submaps(straight_survey(200, 25));
  // 101 soundings per 25 m² sailed: 0.5 m apart.
  EXPECT_NEAR(set.footprint.spacing_m, std::sqrt(199 * 25.0 / (200 * 101)), 1e-6);
  EXPECT_NEAR(set.footprint.altitude_m, 10, 1e-6);
  EXPECT_EQ(build_submaps(Survey{}).footprint.spacing_m, 0);
}

// A ship's line 20 km long, soundings ~18 m apart (a footprint 128 times the lake's), its
// navigation stepping 1.5 m sideways every 400 m as a dead-reckoned track does between fixes: one
// line. With the lake's 10 m course window every step would read as a turn and split it.
TEST(SoundingFootprint, LinesFollowItToo) {
  Survey survey;
  for (int i = 0; i <= 2000; ++i) {
    survey.nav.push_back({.time = 6.0 * i, .easting = 10.0 * i, .northing = 1.5 * (i / 40), .heading_deg = 90});
  }
  for (int i = 0; i < 2000; ++i) {
    survey.pings.push_back({6.0 * i + 3, static_cast<uint32_t>(survey.beams.size()), 101});
    for (int b = 0; b <= 100; ++b) {
      survey.beams.push_back({static_cast<uint32_t>(b), 0, static_cast<float>(3200 * (b / 100.0 - 0.5)), 1500});
    }
  }
  const SubmapSet set = build_submaps(survey);
  EXPECT_EQ(length_scale(set.footprint), 128);
  EXPECT_GT(split_lines(survey.nav).size(), 10u) << "the lake's window sees turns";
  ASSERT_EQ(set.lines.size(), 1u);
  // The ends lie within a course window of the track's ends, where no course is known.
  for (std::size_t i = 1; i + 1 < set.submaps.size(); ++i) EXPECT_EQ(set.submaps[i].line, 0) << i;
}

TEST(FootprintScale, IsThePowerOfTwoNearestTheSpacingOverThePapers) {
  const PipelineConfig measured;
  EXPECT_EQ(footprint_scale({.spacing_m = kPaperSpacingM * 1.3}, measured), 1);  // the lake's varies by a few percent
  EXPECT_EQ(footprint_scale({.spacing_m = kPaperSpacingM / 1.3}, measured), 1);
  EXPECT_EQ(footprint_scale({.spacing_m = kPaperSpacingM * 3.3}, measured), 4);
  EXPECT_EQ(footprint_scale({.spacing_m = 15.7}, measured), 128);  // EX1811, 1.2-2.3 km deep
  EXPECT_EQ(footprint_scale({}, measured), 1);                      // nothing swept
  PipelineConfig given;
  given.footprint.scale = 1;  // Table 1's lengths whatever the survey
  EXPECT_EQ(footprint_scale({.spacing_m = 15.7}, given), 1);
}

TEST(ScaledToFootprint, LengthsAndAreasScaleAndNothingElse) {
  const PipelineConfig config = preset_config(Configuration::kMchs);
  const PipelineConfig scaled = scaled_to_footprint(config, 8);
  EXPECT_DOUBLE_EQ(scaled.grid.cell_m, 4.0);
  EXPECT_FLOAT_EQ(scaled.voxel.leaf_z_m, 0.8f);
  EXPECT_DOUBLE_EQ(scaled.registration.gicp.max_correspondence_m, 24.0);
  EXPECT_DOUBLE_EQ(scaled.registration.uniqueness.search_radius_m, 192.0);
  EXPECT_DOUBLE_EQ(scaled.registration.uniqueness.misfit_floor_m2, 64 * config.registration.uniqueness.misfit_floor_m2);
  EXPECT_DOUBLE_EQ(scaled.acceptance.max_overlap_mse_m2, 320.0);
  EXPECT_DOUBLE_EQ(scaled.keypoints.min_tsd_m, 0.64);
  EXPECT_DOUBLE_EQ(scaled.quality.best_sigma_translation_m.x(), 0.8);
  EXPECT_DOUBLE_EQ(scaled.consistency.cell_m, 8.0);
  // Counts, ratios, cells and the navigation's noise are the same at any depth.
  EXPECT_EQ(scaled.registration.gicp.neighbours, config.registration.gicp.neighbours);
  EXPECT_EQ(scaled.registration.matching.min_ncc, config.registration.matching.min_ncc);
  EXPECT_EQ(scaled.grid.idw_radius_cells, config.grid.idw_radius_cells);
  EXPECT_EQ(scaled.graph.dr_sigma_translation_m, config.graph.dr_sigma_translation_m);
  EXPECT_EQ(parameters(scaled_to_footprint(config, 1)), parameters(config));
}

TEST(ScaledToFootprint, ALengthTheUserSetStaysAsGiven) {
  PipelineConfig config = preset_config(Configuration::kGicp);
  set_parameter(config, "grid.cell_m", "0.7");
  set_parameter(config, "registration.gicp.max_correspondence_m", "5");
  const PipelineConfig scaled = scaled_to_footprint(config, 16);
  EXPECT_DOUBLE_EQ(scaled.grid.cell_m, 0.7);
  EXPECT_DOUBLE_EQ(scaled.registration.gicp.max_correspondence_m, 5.0);
  EXPECT_DOUBLE_EQ(scaled.registration.crop_margin_m, 16.0);
}

}  // namespace
}  // namespace bathyslam
