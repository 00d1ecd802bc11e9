#include "core/pipeline/pipeline_config.h"

#include <stdexcept>
#include <thread>

namespace bathyslam {

Configuration parse_configuration(const std::string& name) {
  for (std::size_t k = 0; k < kConfigurationNames.size(); ++k) {
    if (name == kConfigurationNames[k]) return static_cast<Configuration>(k);
  }
  throw std::invalid_argument("unknown configuration '" + name + "' (expected odometry, gicp or mchs)");
}

std::string to_string(Configuration configuration) {
  const auto k = static_cast<std::size_t>(configuration);
  return k < kConfigurationNames.size() ? kConfigurationNames[k] : "?";
}

PipelineConfig preset_config(Configuration configuration) {
  PipelineConfig config;
  config.configuration = configuration;
  if (configuration == Configuration::kMchs) return config;
  // The paper's baseline registers from dead reckoning: fed back through its uniform weights,
  // its wrong flat-ground edges would steer every later guess.
  config.stages.feature_aided = 0;
  config.stages.quality_aware = 0;
  config.stages.loop_closures = 0;
  config.stages.batch_submaps = 0;
  config.robustness.dr_gate = 0;
  config.robustness.consistency = 0;
  config.robustness.safety_net = 0;
  config.navigation_noise.estimate = 0;
  if (configuration == Configuration::kOdometry) config.stages.registration = 0;
  return config;
}

Plan plan_of(const PipelineConfig& c) {
  Plan plan;
  plan.registration = c.stages.registration != 0;
  plan.features = plan.registration && c.stages.feature_aided;
  plan.quality_aware = plan.registration && c.stages.quality_aware;
  plan.loop_closures = plan.registration && c.stages.loop_closures;
  plan.batch_submaps = plan.registration ? c.stages.batch_submaps : 0;
  plan.dr_gate = plan.registration && c.robustness.dr_gate;
  plan.consistency = plan.registration && c.robustness.consistency;
  plan.safety_net = plan.registration && c.robustness.safety_net;
  plan.direct_loops = plan.loop_closures && plan.quality_aware && c.direct_loops.enabled;
  plan.estimate_noise = plan.registration && c.navigation_noise.estimate;
  plan.alias_from_prior = plan.quality_aware && plan.dr_gate && c.robustness.alias_from_prior;
  plan.alias_from_graph = plan.alias_from_prior && plan.batch_submaps > 0 && c.robustness.alias_from_graph;
  plan.own_gicp = uses_own_gicp(c.registration.gicp);
  plan.hessian_information = plan.quality_aware && c.quality.information_from_hessian;
  plan.threads = c.threads > 0 ? c.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  return plan;
}

}  // namespace bathyslam
