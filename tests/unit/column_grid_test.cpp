// The column grid's nearest neighbours are a brute-force search's, in 3-D, whatever the layout:
// a rough seabed, a near-vertical wall (many points per column), a line with no width, and
// queries outside the grid, with and without a mask and a bound.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "core/register/column_grid.h"

namespace bathyslam {
namespace {

std::vector<float> brute_force(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f& query, std::size_t k,
                               float max_sq, const std::vector<uint8_t>& allowed) {
  std::vector<float> d;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const float sq = (query - points[i]).squaredNorm();
    if ((allowed.empty() || allowed[i]) && sq < max_sq) d.push_back(sq);
  }
  std::sort(d.begin(), d.end());
  d.resize(std::min(k, d.size()));
  return d;
}

void expect_brute_force(const std::vector<Eigen::Vector3f>& points, const std::vector<Eigen::Vector3f>& queries,
                        const std::vector<uint8_t>& allowed) {
  const ColumnGrid grid(points);
  const uint8_t* mask = allowed.empty() ? nullptr : allowed.data();
  for (std::size_t k : {1u, 4u, 20u}) {
    for (float max_sq : {0.3f, 4.0f, INFINITY}) {
      for (const Eigen::Vector3f& q : queries) {
        std::vector<uint32_t> index(k);
        std::vector<float> sq(k);
        const std::size_t found = grid.nearest_within(q, k, max_sq, mask, index.data(), sq.data());
        const std::vector<float> expected = brute_force(points, q, k, max_sq, allowed);
        ASSERT_EQ(found, expected.size()) << "k " << k << " bound " << max_sq << " at " << q.transpose();
        for (std::size_t n = 0; n < found; ++n) {
          // Ties may come in either order: the distances must agree, and belong to the indices.
          ASSERT_FLOAT_EQ(sq[n], expected[n]) << "k " << k << ", neighbour " << n;
          ASSERT_FLOAT_EQ((q - points[index[n]]).squaredNorm(), sq[n]);
          if (mask != nullptr) {
            ASSERT_TRUE(allowed[index[n]]);
          }
        }
      }
    }
  }
}

std::vector<Eigen::Vector3f> queries_around(const std::vector<Eigen::Vector3f>& points, std::mt19937& rng) {
  std::vector<Eigen::Vector3f> queries;
  std::uniform_int_distribution<std::size_t> pick(0, points.size() - 1);
  std::normal_distribution<float> jitter(0, 0.7f);
  for (int n = 0; n < 150; ++n) queries.push_back(points[pick(rng)] + Eigen::Vector3f(jitter(rng), jitter(rng), jitter(rng)));
  // Outside the grid, near and far.
  queries.push_back(Eigen::Vector3f(-3, -3, 0));
  queries.push_back(Eigen::Vector3f(60, 2, -5));
  queries.push_back(Eigen::Vector3f(1e5f, -1e5f, 0));
  return queries;
}

TEST(ColumnGrid, FindsWhatBruteForceFindsOnARoughSeabed) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> along(0, 40), across(0, 25), rough(-0.3f, 0.3f);
  std::vector<Eigen::Vector3f> points;
  for (int i = 0; i < 3000; ++i) {
    const float x = along(rng), y = across(rng);
    points.emplace_back(x, y, -20 + 2 * std::sin(x / 5) + rough(rng));
  }
  const std::vector<Eigen::Vector3f> queries = queries_around(points, rng);
  expect_brute_force(points, queries, {});
  std::vector<uint8_t> allowed(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) allowed[i] = points[i].x() < 25 && i % 3 != 0;
  expect_brute_force(points, queries, allowed);
}

TEST(ColumnGrid, FindsWhatBruteForceFindsOnAWallAndAlongALine) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> unit(0, 1);
  std::vector<Eigen::Vector3f> wall;  // 20 m high, 30 cm thick: dozens of points per column
  for (int i = 0; i < 2000; ++i) wall.emplace_back(10 * unit(rng), 5 + 0.3f * unit(rng), -40 + 20 * unit(rng));
  expect_brute_force(wall, queries_around(wall, rng), {});
  std::vector<Eigen::Vector3f> line;  // no width at all: one row of columns
  for (int i = 0; i < 1000; ++i) line.emplace_back(50 * unit(rng), 2, -10 + 0.1f * unit(rng));
  expect_brute_force(line, queries_around(line, rng), {});
}

TEST(ColumnGrid, AnEmptyGridOrANonFiniteQueryFindsNothing) {
  uint32_t index = 0;
  float sq = 0;
  EXPECT_EQ(ColumnGrid({}).nearest_within(Eigen::Vector3f::Zero(), 1, INFINITY, nullptr, &index, &sq), 0u);
  const ColumnGrid grid({Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(1, 1, 0)});
  EXPECT_EQ(grid.nearest_within(Eigen::Vector3f(NAN, 0, 0), 1, INFINITY, nullptr, &index, &sq), 0u);
  EXPECT_EQ(grid.nearest_within(Eigen::Vector3f(0, INFINITY, 0), 1, INFINITY, nullptr, &index, &sq), 0u);
  EXPECT_EQ(grid.nearest_within(Eigen::Vector3f(0.9f, 0.9f, 0), 1, INFINITY, nullptr, &index, &sq), 1u);
  EXPECT_EQ(index, 1u);
}

// The sample keeps one point per occupied column: every point has a sample point within a column's
// diagonal, no point twice, and a dense patch is thinned to the columns it covers.
TEST(ColumnGrid, CentralPointsAreOnePerOccupiedColumn) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> wide(0, 20), patch(5, 10), depth(-0.2f, 0.2f);
  std::vector<Eigen::Vector3f> points;
  for (int n = 0; n < 4000; ++n) points.emplace_back(wide(rng), wide(rng), depth(rng));
  for (int n = 0; n < 4000; ++n) points.emplace_back(patch(rng), patch(rng), depth(rng));
  const double per_column = 4;
  const ColumnGrid grid(points, per_column);
  const std::vector<uint32_t> sample = grid.central_points();
  std::vector<uint32_t> sorted = sample;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_TRUE(std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end()) << "a point twice";
  EXPECT_GT(sample.size(), points.size() / 8);
  EXPECT_LT(sample.size(), points.size() / 3);
  std::vector<Eigen::Vector3f> kept;
  std::size_t in_patch = 0;
  for (uint32_t i : sample) {
    ASSERT_LT(i, points.size());
    kept.push_back(points[i]);
    in_patch += (points[i].head<2>().array() >= 5).all() && (points[i].head<2>().array() <= 10).all() ? 1 : 0;
  }
  // The patch's 25 m² hold ~4250 points and ~25 / cell² columns.
  const double patch_columns = 25 / (grid.cell_m() * grid.cell_m());
  EXPECT_LT(static_cast<double>(in_patch), 1.3 * patch_columns);
  const ColumnGrid sample_grid(kept);
  const float diagonal_sq = 2 * grid.cell_m() * grid.cell_m();
  for (std::size_t i = 0; i < points.size(); i += 7) {
    uint32_t index = 0;
    float sq = 0;
    ASSERT_EQ(sample_grid.nearest_within(points[i], 1, INFINITY, nullptr, &index, &sq), 1u);
    // Its column's sample is within the diagonal horizontally and 0.4 m in depth.
    EXPECT_LE((kept[index] - points[i]).head<2>().squaredNorm(), diagonal_sq + 0.4f * 0.4f) << i;
  }
}

}  // namespace
}  // namespace bathyslam
