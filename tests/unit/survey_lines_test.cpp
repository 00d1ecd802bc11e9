#include "core/lines/survey_lines.h"

#include <gtest/gtest.h>

#include "core/sim/trajectory.h"

namespace bathyslam {
namespace {

std::vector<NavSample> truth_of(sim::Scenario scenario) {
  return sim::navigation_of(sim::drive(sim::survey_pattern(scenario), sim::MotionConfig{}), 4);
}

double course_of(const sim::LineSpec& line) {
  const Eigen::Vector2d d = line.end - line.start;
  const double c = std::atan2(d.x(), d.y()) * 180 / M_PI;
  return c < 0 ? c + 360 : c;
}

double angle_between(double a, double b) {
  const double d = std::fmod(std::abs(a - b), 360.0);
  return d > 180 ? 360 - d : d;
}

// Every planned line is found, in order, with its course and most of its length; the only
// other straight legs are transits, at most one between two planned lines.
void expect_planned_lines_found(sim::Scenario scenario) {
  const auto planned = sim::survey_pattern(scenario);
  const auto found = split_lines(truth_of(scenario));
  std::size_t next = 0;
  for (const sim::LineSpec& line : planned) {
    const double length = (line.end - line.start).norm();
    while (next < found.size() && angle_between(found[next].course_deg, course_of(line)) > 2.0) ++next;
    ASSERT_LT(next, found.size()) << "planned line at course " << course_of(line) << " not found";
    EXPECT_GT(found[next].length_m, 0.8 * length);
    EXPECT_LT(found[next].length_m, length + 25.0);
    ++next;
  }
  EXPECT_LT(found.size(), 2 * planned.size());
}

TEST(SplitLines, FindsEveryLineOfTheLakePattern) { expect_planned_lines_found(sim::Scenario::kLake); }

TEST(SplitLines, FindsEveryLineOfTheSmallPattern) { expect_planned_lines_found(sim::Scenario::kSmall); }

TEST(SplitLines, AStraightRunIsOneLineAndACircleIsNone) {
  std::vector<NavSample> straight, circle;
  for (int i = 0; i < 500; ++i) {
    straight.push_back({i * 0.5, i * 1.0, 0.5 * i, 1, 0, 0, 63.4});
    const double a = i * 0.05;
    circle.push_back({i * 0.5, 30 * std::sin(a), 30 * std::cos(a), 1, 0, 0, 0});
  }
  ASSERT_EQ(split_lines(straight).size(), 1u);
  EXPECT_NEAR(split_lines(straight)[0].course_deg, std::atan2(1.0, 0.5) * 180 / M_PI, 1e-6);
  EXPECT_TRUE(split_lines(circle).empty());
}

}  // namespace
}  // namespace bathyslam
