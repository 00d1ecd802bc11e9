#include "core/summary/survey_summary.h"

#include <gtest/gtest.h>

namespace bathyslam {
namespace {

TEST(SurveySummary, CountsExtentAndDriftAgainstReference) {
  Survey s;
  s.metadata = {"t", "EPSG:32651", {}, {}};
  for (int i = 0; i <= 100; ++i) s.nav.push_back({100.0 + i, 1000.0 + 2 * i, 500.0, 2.0, 0, 0, 90});
  s.reference_nav = s.nav;
  // Dead reckoning ends 3 m north of the truth, drifting linearly.
  for (int i = 0; i <= 100; ++i) s.nav[i].northing += 0.03 * i;
  s.pings = {{100.5, 0, 2}, {101.5, 2, 1}};
  s.beams = {{0, 0, -1, 9}, {1, 0, 1, 9}, {0, 0, 0, 9}};

  const SurveySummary summary = summarize(s);
  EXPECT_EQ(summary.pings, 2u);
  EXPECT_EQ(summary.soundings, 3u);
  EXPECT_EQ(summary.nav_samples, 101u);
  EXPECT_DOUBLE_EQ(summary.time_end - summary.time_begin, 100.0);
  EXPECT_DOUBLE_EQ(summary.easting_max - summary.easting_min, 200.0);
  EXPECT_EQ(summary.lines.size(), 1u);
  ASSERT_TRUE(summary.drift);
  EXPECT_NEAR(summary.drift->end_m, 3.0, 1e-9);
  EXPECT_NEAR(summary.drift->mean_m, 1.5, 1e-9);
  const nlohmann::json j = to_json(summary);
  EXPECT_EQ(j["counts"]["soundings"], 3);
  EXPECT_EQ(j["line_count"], 1);
  EXPECT_NEAR(j["drift"]["end_m"].get<double>(), 3.0, 1e-9);
  EXPECT_NE(to_text(summary).find("3.00 m at the end"), std::string::npos);
}

}  // namespace
}  // namespace bathyslam
