#pragma once
// navigation_noise: how noisy this survey's dead reckoning is, estimated from the survey itself.
//
// Table 1's DR sigmas (5 m and 0.01 rad per step) are a prior, not a measurement: a DVL/INS drifts
// tens of times less, a compass-only vehicle more. Every registration that carries horizontal
// information is a noisy observation of how far dead reckoning drifted between its two submaps:
// its innovation d (measured − DR, in x, y and yaw) has covariance S(θ) = s_t²·A + s_ψ²·B + R,
// A and B the DR chain's covariance per unit of the prior's x/y and yaw variances (dr_noise.h,
// linear in them) and R the registration's own. The scales (s_t, s_ψ) maximise the likelihood
// of the innovations the noise explains: a first fit under Huber's loss, then the Gaussian
// likelihood of the innovations within χ²₃ 99.9 % of it, trimmed again under each new fit, so
// that a few wrong registrations do not pass for a noisy navigation. Innovations that share DR steps are taken as independent (a
// composite likelihood: consistent, its confidence overstated, which only the estimate's
// report would show). The scales are bounded to [min_scale, 1]: never looser than Table 1.
// The graph gets the loosest heading noise the innovations do not rule out (profile likelihood
// within χ²₁ 95 % of its maximum), with the translation noise that fits best beside it, not the
// likeliest pair: a few innovations leave heading and position noise interchangeable along a
// ridge of the likelihood, and its likeliest point then stiffens the heading by a decade at random
// (channel heading-walk seed 1: one more loop moved 0.11 m / 0.0078 rad to 0.36 m / 0.0022 rad a
// step, and the trajectory from 0.70 to 2.70 m). A heading too stiff narrows dead reckoning's
// long-range covariance, so the DR gate refuses right loops and the odometry cannot turn where
// the navigation did; translation noise too loose lets the lines stretch where no registration
// observes them (the same survey, 0.75 m a step: the map worse than dead reckoning's). So the
// point moves along the ridge towards heading, and both are never loosened at once, which the
// likelihood would rule out. What many innovations pin down stays where they pin it. A looser
// prior also rules out fewer of a registration's aliases, and refusing a right answer as
// ambiguous costs the map what bending gains it (channel paper seed 1), so aliases are judged
// under the likeliest scales (`likeliest_graph`), as they were before, unless the likeliest heading
// sits at its bound (alias_graph).
//
// A compass step (a heading fault: one large error among small ones) is no white noise: the
// registrations across it disagree with dead reckoning by about the same turn, and a sigma small
// enough for the rest trims them all as outliers, after which the DR gate refuses every right
// answer across the step and the stiff odometry cannot bend there. So the heading jump that best
// explains the innovations across it (their positions through the lever arms and their yaw) is
// tried as that step's own yaw variance (its size squared); it is kept when at least
// min_registrations more innovations are explained, and the search goes on, up to
// max_heading_steps.
#include <vector>

#include <Eigen/Geometry>

#include "core/graph/dr_noise.h"
#include "core/graph/pose_graph.h"
#include "core/types/fields.h"

namespace bathyslam {

struct NavigationNoiseConfig {
  // 0: Table 1's DR sigmas throughout, as in the paper.
  bool estimate = true;
  // Fewer innovations than this say too little: the prior stays.
  int min_registrations = 3;
  // The least scale of the prior's x/y and yaw sigmas (5 mm and 1e-5 rad per step by default).
  double min_scale = 1e-3;
  // On each innovation's squared Mahalanobis distance: Huber's threshold in the first fit, and
  // beyond it an innovation the noise does not explain (χ²₃ at 99.9 %). Huber alone still let
  // four 25 m outliers among 79 widen the translation sigma elevenfold (navigation_noise_test.cpp).
  double outlier_chi2 = 16.27;
  // Heading steps looked for; 0: one white sigma for every step, as before.
  int max_heading_steps = 3;
  // The profile likelihood's rise that bounds the published heading scale from above (χ²₁ at
  // 95 %); 0: the likeliest scales.
  double confidence_chi2 = 3.84;

  template <typename Field>
  void fields(Field&& field) {
    field("estimate", estimate, 0, 1);
    field("min_registrations", min_registrations, 1, 1000000);
    field("min_scale", min_scale, 1e-6, 1);
    field("outlier_chi2", outlier_chi2, 0.1, 1e6);
    field("max_heading_steps", max_heading_steps, 0, 100);
    field("confidence_chi2", confidence_chi2, 0, 1000);
  }
};

// One registration as an observation of DR's drift between `from` and `to`, in dr_noise.h's
// parametrisation (the DR gate's own difference and measurement covariance).
struct DrInnovation {
  int from = 0;
  int to = 0;
  Vector6 difference = Vector6::Zero();           // measured − DR (pose_difference)
  Covariance6 measurement = Covariance6::Zero();  // the registration's
};

// `edge` (a registration) against dead reckoning: the DR gate's difference and the edge's own
// measurement covariance, as loop_candidate levels them.
DrInnovation dr_innovation(const PoseGraphEdge& edge, const DrNoiseModel& dr,
                           const std::vector<Eigen::Isometry3d>& dead_reckoning);

struct NavigationNoiseEstimate {
  bool estimated = false;  // false: too few innovations, `graph` is the prior
  int innovations = 0;
  double translation_scale = 1;  // of the prior's x and y sigmas, as the graph gets them
  double yaw_scale = 1;          // of the prior's yaw sigma, as the graph gets them
  double likeliest_translation_scale = 1, likeliest_yaw_scale = 1;  // the maximum of the likelihood
  GraphConfig graph;             // the prior with its x, y and yaw sigmas scaled, and the heading steps
  GraphConfig likeliest_graph;   // the same at the likeliest scales, which rule out aliases
  struct HeadingStep {
    int step = 0;         // of the odometry step from node `step` to the next
    double jump_rad = 0;  // DR's heading jump there, as the registrations across it show it
    int explained = 0;    // innovations explained once it is modelled, not before
  };
  std::vector<HeadingStep> heading_steps;
};

// The noise model aliases are judged under: the likeliest scales where the likelihood has its
// maximum inside their range. At the least yaw scale allowed it says only that the innovations so
// far show no heading drift (a few registrations that agree), which is no evidence that dead
// reckoning rules an alias out; there the loosest heading not ruled out (`graph`) judges them too
// (`lake`-size slope break heading-walk seed 2: 9 innovations, the likeliest at its bound, a loop
// whose every alias it "ruled out" kept 23.7 m off at 32 sigma).
GraphConfig alias_graph(const NavigationNoiseEstimate& estimate, const NavigationNoiseConfig& config);

// The maximum-likelihood scales over grids in log space (0.2 decades over the whole range, then
// 0.05 and 0.01 about the best), which the likelihood's few local minima do not mislead.
// `known_steps` (an earlier estimate's) are kept as found, new ones looked for beside them.
NavigationNoiseEstimate estimate_navigation_noise(const std::vector<Eigen::Isometry3d>& dead_reckoning,
                                                  const std::vector<DrInnovation>& innovations, const GraphConfig& prior,
                                                  const NavigationNoiseConfig& config,
                                                  const std::vector<NavigationNoiseEstimate::HeadingStep>& known_steps = {});

}  // namespace bathyslam
