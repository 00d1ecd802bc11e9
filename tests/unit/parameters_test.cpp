#include "core/pipeline/pipeline.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace bathyslam {
namespace {

using ::testing::HasSubstr;

TEST(Parameters, SetByNameReachesTheStageConfig) {
  PipelineConfig config;
  set_parameter(config, "gicp.max_iterations", "120");
  set_parameter(config, "voxel.leaf_z_m", "0.25");
  set_parameter(config, "graph.dr_sigma_yaw_rad", "0.02");
  EXPECT_EQ(config.registration.gicp.max_iterations, 120);
  EXPECT_FLOAT_EQ(config.voxel.leaf_z_m, 0.25f);
  EXPECT_DOUBLE_EQ(config.graph.dr_sigma_rotation_rad.z(), 0.02);
  const auto all = parameters(config);
  EXPECT_EQ(all.at("gicp.max_iterations"), 120.0);
  EXPECT_EQ(all.at("gicp.max_correspondence_m"), 3.0);  // Table 1 default untouched
}

TEST(Parameters, GicpEngineIsOursUnlessAskedForPcl) {
  PipelineConfig config;
  EXPECT_EQ(parameters(config).at("gicp.engine"), 1.0);
  set_parameter(config, "gicp.engine=0");
  EXPECT_EQ(config.registration.gicp.engine, 0);
  EXPECT_THROW(set_parameter(config, "gicp.engine=2"), std::invalid_argument);
  EXPECT_EQ(config.registration.gicp.engine, 0);
}

TEST(Parameters, BadNamesAndValuesAreRejectedByName) {
  PipelineConfig config;
  auto message = [&](const std::string& name, const std::string& value) {
    try {
      set_parameter(config, name, value);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_THAT(message("gicp.iterations", "10"), HasSubstr("unknown parameter 'gicp.iterations'"));
  EXPECT_THAT(message("gicp.max_iterations", "12.5"), HasSubstr("or not an integer"));
  EXPECT_THAT(message("gicp.max_iterations", "-3"), HasSubstr("is outside"));
  EXPECT_THAT(message("voxel.leaf_x_m", "0.2m"), HasSubstr("'0.2m' is not a number"));
  EXPECT_THAT(message("voxel.leaf_x_m", ""), HasSubstr("'' is not a number"));
  EXPECT_EQ(config.registration.gicp.max_iterations, 300) << "a rejected value changes nothing";
}

TEST(Parameters, StoredNumbersAndNameValueArgumentsGoThroughTheSameChecks) {
  PipelineConfig config;
  set_parameter(config, "candidates.k_adjacent_lines", 2.0);  // a job's or a report's stored value
  set_parameter(config, "gicp.neighbours=25");                // a --set argument
  EXPECT_EQ(config.candidates.k_adjacent_lines, 2);
  EXPECT_EQ(config.registration.gicp.neighbours, 25);
  auto message = [&](auto&&... arguments) {
    try {
      set_parameter(config, arguments...);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_THAT(message("candidates.k_adjacent_lines", 2.5), HasSubstr("parameter 'candidates.k_adjacent_lines': 2.5 is outside"));
  EXPECT_THAT(message(std::string_view("gicp.neighbours25")), HasSubstr("expected name=value, got 'gicp.neighbours25'"));
  EXPECT_THAT(message(std::string_view("gicp.neighbour=25")), HasSubstr("unknown parameter 'gicp.neighbour'"));
  EXPECT_EQ(config.registration.gicp.neighbours, 25) << "a rejected value changes nothing";
}

}  // namespace
}  // namespace bathyslam
