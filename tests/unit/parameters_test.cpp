#include "core/pipeline/parameters.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <string>
#include <new>

namespace bathyslam {
namespace {

using ::testing::HasSubstr;

TEST(Parameters, SetByNameReachesTheStageConfig) {
  PipelineConfig config;
  set_parameter(config, "registration.gicp.max_iterations", "120");
  set_parameter(config, "voxel.leaf_z_m", "0.25");
  set_parameter(config, "graph.dr_sigma_rotation_rad.yaw", "0.02");
  EXPECT_EQ(config.registration.gicp.max_iterations, 120);
  EXPECT_FLOAT_EQ(config.voxel.leaf_z_m, 0.25f);
  EXPECT_DOUBLE_EQ(config.graph.dr_sigma_rotation_rad.z(), 0.02);
  const auto all = parameters(config);
  EXPECT_EQ(all.at("registration.gicp.max_iterations"), 120.0);
  EXPECT_EQ(all.at("registration.gicp.max_correspondence_m"), 3.0);  // Table 1 default untouched
}

TEST(Parameters, GicpEngineIsOursUnlessAskedForPcls) {
  PipelineConfig config;
  EXPECT_EQ(parameters(config).at("registration.gicp.engine"), 1.0);
  set_parameter(config, "registration.gicp.engine=0");
  EXPECT_EQ(config.registration.gicp.engine, 0);
  EXPECT_THROW(set_parameter(config, "registration.gicp.engine=2"), std::invalid_argument);
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
  EXPECT_THAT(message("registration.gicp.iterations", "10"), HasSubstr("unknown parameter 'registration.gicp.iterations'"));
  EXPECT_THAT(message("registration.gicp.max_iterations", "12.5"), HasSubstr("or not an integer"));
  EXPECT_THAT(message("registration.gicp.max_iterations", "-3"), HasSubstr("is outside"));
  EXPECT_THAT(message("voxel.leaf_x_m", "0.2m"), HasSubstr("'0.2m' is not a number"));
  EXPECT_THAT(message("voxel.leaf_x_m", ""), HasSubstr("'' is not a number"));
  EXPECT_THAT(message("keypoints.descriptor_size", "8"), HasSubstr("is even"));  // it would have no centre
  EXPECT_EQ(config.registration.gicp.max_iterations, 300) << "a rejected value changes nothing";
  EXPECT_EQ(config.keypoints.descriptor_size, 11);
}

TEST(Parameters, StoredNumbersAndNameValueArgumentsGoThroughTheSameChecks) {
  PipelineConfig config;
  set_parameter(config, "candidates.k_adjacent_lines", 2.0);  // a job's or a report's stored value
  set_parameter(config, "registration.gicp.neighbours=25");   // a --set argument
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
  EXPECT_THAT(message(std::string_view("registration.gicp.neighbours25")),
              HasSubstr("expected name=value, got 'registration.gicp.neighbours25'"));
  EXPECT_THAT(message(std::string_view("registration.gicp.neighbour=25")),
              HasSubstr("unknown parameter 'registration.gicp.neighbour'"));
  EXPECT_EQ(config.registration.gicp.neighbours, 25) << "a rejected value changes nothing";
}

// Names from before they followed the fields' paths, as stored jobs and old scripts have them.
TEST(Parameters, OldNamesStillSetTheirFields) {
  PipelineConfig config;
  set_parameter(config, "gicp.neighbours", "25");
  set_parameter(config, "gicp.sigma_yaw_rad", "0.05");
  set_parameter(config, "robust.pair_chi2", "20");
  set_parameter(config, "accept.min_distinctness", "30");
  set_parameter(config, "batch_submaps", "4");
  EXPECT_EQ(config.registration.gicp.neighbours, 25);
  EXPECT_DOUBLE_EQ(config.uniform_information.sigma_rotation_rad.z(), 0.05);
  EXPECT_DOUBLE_EQ(config.robustness.pcm.pair_chi2_threshold, 20);
  EXPECT_DOUBLE_EQ(config.acceptance.min_distinctness, 30);
  EXPECT_EQ(config.stages.batch_submaps, 4);
}

// Every byte of the configuration is a parameter or padding: a field added without its line in
// `fields` fails here. Padding is found by constructing the config over two different byte
// patterns: default member initializers write the fields and leave the padding alone.
TEST(Parameters, EveryFieldOfTheConfigurationIsAParameter) {
  alignas(PipelineConfig) unsigned char zeros[sizeof(PipelineConfig)], ones[sizeof(PipelineConfig)];
  std::memset(zeros, 0x00, sizeof zeros);
  std::memset(ones, 0xff, sizeof ones);
  auto* a = new (zeros) PipelineConfig;
  auto* b = new (ones) PipelineConfig;
  std::vector<bool> covered(sizeof(PipelineConfig), false);
  for (std::size_t i = 0; i < sizeof(PipelineConfig); ++i) covered[i] = zeros[i] != ones[i];  // padding
  auto cover = [&](const void* field, std::size_t size) {
    const std::size_t offset = static_cast<const unsigned char*>(field) - zeros;
    for (std::size_t i = offset; i < offset + size; ++i) covered[i] = true;
  };
  cover(&a->configuration, sizeof a->configuration);  // the preset's name, not a parameter
  cover(&a->graph.step_yaw_sigma_rad, sizeof a->graph.step_yaw_sigma_rad);  // found in the survey, not set
  cover(&a->graph.survey_starts, sizeof a->graph.survey_starts);  // the job's surveys, not set
  std::vector<std::string> names;
  a->fields([&](std::string_view name, auto& field, double min, double max) {
    names.emplace_back(name);
    cover(&field, sizeof field);
    EXPECT_LE(min, max) << name;
  });
  for (std::size_t i = 0; i < covered.size(); ++i) EXPECT_TRUE(covered[i]) << "byte " << i << " is in no parameter";
  EXPECT_EQ(parameters(*a).size(), names.size()) << "two fields share a name";
  a->~PipelineConfig();
  b->~PipelineConfig();
}

// Each parameter set to another value in its range reads back as that value and changes no other.
TEST(Parameters, EachParameterSetsItsOwnFieldOnly) {
  const std::map<std::string, double> defaults = parameters(PipelineConfig{});
  PipelineConfig probe;
  std::map<std::string, std::pair<double, double>> ranges;
  probe.fields([&](std::string_view name, auto&, double min, double max) { ranges[std::string(name)] = {min, max}; });
  for (const auto& [name, range] : ranges) {
    const double value = defaults.at(name) == range.first ? range.second : range.first;
    PipelineConfig config;
    set_parameter(config, name, value);
    const std::map<std::string, double> got = parameters(config);
    for (const auto& [other, was] : defaults) {
      if (other == name) {
        EXPECT_NEAR(got.at(other), value, 1e-6 * std::max(1.0, std::abs(value))) << name;  // float fields round
      } else {
        EXPECT_EQ(got.at(other), was) << "setting " << name << " changed " << other;
      }
    }
  }
}

TEST(Configurations, ArePresetsOfTheStagesAndEveryAblationIsASetting) {
  const Plan mchs = plan_of(preset_config(Configuration::kMchs));
  EXPECT_TRUE(mchs.registration && mchs.features && mchs.quality_aware && mchs.loop_closures);
  EXPECT_TRUE(mchs.dr_gate && mchs.consistency && mchs.safety_net);
  EXPECT_EQ(mchs.batch_submaps, 10);
  const Plan gicp = plan_of(preset_config(Configuration::kGicp));
  EXPECT_TRUE(gicp.registration);
  EXPECT_FALSE(gicp.features || gicp.quality_aware || gicp.loop_closures || gicp.dr_gate || gicp.consistency || gicp.safety_net);
  EXPECT_EQ(gicp.batch_submaps, 0);
  const Plan odometry = plan_of(preset_config(Configuration::kOdometry));
  EXPECT_FALSE(odometry.registration || odometry.features || odometry.safety_net);

  PipelineConfig no_loops = preset_config(Configuration::kMchs);
  set_parameter(no_loops, "stages.loop_closures=0");
  EXPECT_FALSE(plan_of(no_loops).loop_closures);
  EXPECT_TRUE(plan_of(no_loops).features);
  PipelineConfig batched_gicp = preset_config(Configuration::kGicp);
  set_parameter(batched_gicp, "stages.batch_submaps=5");
  EXPECT_EQ(plan_of(batched_gicp).batch_submaps, 5);
  for (const char* name : kConfigurationNames) EXPECT_EQ(to_string(parse_configuration(name)), name);
  EXPECT_THROW(parse_configuration("slam"), std::invalid_argument);
}

// The CLI, the service and the scheduler make a configuration the same way: the preset (none
// named: mchs), then the overrides by name; a bad one is named as a request names it.
TEST(Parameters, OneWayFromAPresetAndOverridesToAConfiguration) {
  const PipelineConfig none_named = configuration_of("", std::map<std::string, std::string>{});
  EXPECT_EQ(none_named.configuration, Configuration::kMchs);
  EXPECT_EQ(parameters(none_named), parameters(preset_config(Configuration::kMchs)));

  const PipelineConfig gicp = configuration_of("gicp", {{"registration.gicp.neighbours", "25"}, {"stages.batch_submaps", "5"}});
  EXPECT_EQ(gicp.configuration, Configuration::kGicp);
  EXPECT_EQ(gicp.registration.gicp.neighbours, 25);
  EXPECT_EQ(gicp.stages.batch_submaps, 5);
  // A stored job's numbers give the same configuration as the text a user typed.
  EXPECT_EQ(parameters(configuration_of("gicp", std::map<std::string, double>{{"registration.gicp.neighbours", 25.0},
                                                                               {"stages.batch_submaps", 5.0}})),
            parameters(gicp));

  auto field_of = [](auto&& make) -> std::string {
    try {
      make();
    } catch (const ConfigurationError& error) {
      return error.field() + ": " + error.what();
    }
    return "no error";
  };
  EXPECT_THAT(field_of([] { configuration_of("slam", std::map<std::string, std::string>{}); }), HasSubstr("configuration: "));
  // In name order: of two bad overrides the first by name is the one named, whatever the request's order.
  EXPECT_THAT(field_of([] { configuration_of("mchs", {{"z.unknown", "1"}, {"grid.cell_m", "-1"}}); }),
              HasSubstr("parameters[grid.cell_m]: "));
  EXPECT_THAT(field_of([] { overrides_of({"grid.cell_m"}); }), HasSubstr("expected name=value"));

  const std::map<std::string, std::string> sets = overrides_of({"grid.cell_m=0.7", "grid.cell_m=0.9"});
  EXPECT_EQ(sets.at("grid.cell_m"), "0.9") << "the last of a name wins, as the arguments were applied in order";
}

}  // namespace
}  // namespace bathyslam
