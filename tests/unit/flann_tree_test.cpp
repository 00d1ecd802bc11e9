#include "core/search/flann_tree.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <pcl/kdtree/kdtree_flann.h>

namespace bathyslam {
namespace {

// A rough seabed patch with a few invalid soundings, which both trees must skip alike.
pcl::PointCloud<pcl::PointXYZ>::Ptr seabed_patch() {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> along(-20.0f, 20.0f), depth(-0.3f, 0.3f);
  auto cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  for (int i = 0; i < 3000; ++i) {
    const float x = along(rng), y = along(rng);
    cloud->push_back(pcl::PointXYZ(x, y, 30.0f + 0.5f * std::sin(0.3f * x) + depth(rng)));
  }
  for (int i : {5, 1234, 2999}) (*cloud)[i].z = NAN;
  cloud->is_dense = false;
  return cloud;
}

TEST(FlannTree, FindsPclsNeighboursAndDistancesExactly) {
  const auto cloud = seabed_patch();
  pcl::KdTreeFLANN<pcl::PointXYZ> pcl_tree;
  pcl_tree.setInputCloud(cloud);
  FlannTree tree;
  tree.setInputCloud(cloud);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> along(-25.0f, 25.0f), depth(29.0f, 31.0f);
  for (int k : {1, 20, 300}) {  // 300: FLANN's other result set (above KNN_HEAP_THRESHOLD)
    for (int q = 0; q < 200; ++q) {
      const pcl::PointXYZ query(along(rng), along(rng), depth(rng));
      pcl::Indices expected, got;
      std::vector<float> expected_sq, got_sq;
      ASSERT_EQ(tree.nearestKSearch(query, k, got, got_sq), pcl_tree.nearestKSearch(query, k, expected, expected_sq));
      EXPECT_EQ(got, expected) << "k " << k << ", query " << q;
      EXPECT_EQ(got_sq, expected_sq) << "k " << k << ", query " << q;
    }
  }
}

TEST(FlannTree, PlanarRadiusSearchIsPclsExactly) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> along(-60.0, 60.0);
  std::vector<Eigen::Vector3d> keypoints;
  auto cloud = std::make_shared<pcl::PointCloud<pcl::PointXY>>();
  for (int i = 0; i < 1500; ++i) {
    // Rounded to a 0.5 m grid, as keypoints are: many points at equal distances.
    keypoints.emplace_back(0.5 * std::round(2 * along(rng)), 0.5 * std::round(2 * along(rng)), 20.0);
    pcl::PointXY p;
    p.x = static_cast<float>(keypoints.back().x());
    p.y = static_cast<float>(keypoints.back().y());
    cloud->push_back(p);
  }
  pcl::KdTreeFLANN<pcl::PointXY> pcl_tree;
  pcl_tree.setInputCloud(cloud);
  const FlannIndex tree = planar_index(keypoints);
  for (int q = 0; q < 200; ++q) {
    pcl::PointXY query;
    query.x = static_cast<float>(along(rng));
    query.y = static_cast<float>(along(rng));
    const float xy[2] = {query.x, query.y};
    pcl::Indices expected, got;
    std::vector<float> expected_sq, got_sq;
    ASSERT_EQ(tree.within(xy, 30.0, got, got_sq), pcl_tree.radiusSearch(query, 30.0, expected, expected_sq));
    EXPECT_EQ(got, expected) << "query " << q;
    EXPECT_EQ(got_sq, expected_sq) << "query " << q;
  }
}

TEST(FlannTree, AnEmptyCloudFindsNothing) {
  FlannTree tree;
  tree.setInputCloud(std::make_shared<pcl::PointCloud<pcl::PointXYZ>>());
  pcl::Indices found;
  std::vector<float> sq;
  EXPECT_EQ(tree.nearestKSearch(pcl::PointXYZ(0, 0, 0), 5, found, sq), 0);
  EXPECT_TRUE(found.empty());
}

}  // namespace
}  // namespace bathyslam
