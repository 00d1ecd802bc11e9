#pragma once
// The registration stage: candidate submap pairs registered into constraints, in parallel, the
// way the plan says (direct or switched, tested and weighed by quality or uniformly, gated
// against dead reckoning or not).
#include <atomic>
#include <vector>

#include "core/candidates/candidates.h"
#include "core/filter/voxel_filter.h"
#include "core/graph/dr_noise.h"
#include "core/pipeline/constraint.h"
#include "core/pipeline/pipeline_config.h"

namespace bathyslam {

struct Candidate {
  CandidatePair pair;  // source = `to`, target = `from`
  ConstraintType type = ConstraintType::kAdjacent;
};

// What registration reads besides the pairs: per submap its filtered cloud for PCL's GICP
// (gicp.engine 0; empty with ours), or prepared once for ours when it first registers
// (gicp.engine 1), and (with plan.features) its features; dead reckoning and its noise model
// (the survey's estimate so far) for the DR gate and the direct loops' reach, and at its
// likeliest for the aliases where the data determine it (alias_graph, judge_with_prior).
struct RegistrationInputs {
  const std::vector<Cloud::Ptr>& clouds;
  GicpCloudCache& prepared;
  const std::vector<SubmapFeatures>& features;
  const std::vector<Eigen::Isometry3d>& dr_poses;
  const DrNoiseModel& dr;
  const DrNoiseModel& alias_dr;
};

// One constraint per candidate, in candidate order, each registered from the guess `estimate`
// gives. Throws Cancelled when `cancel` is set.
std::vector<Constraint> register_pairs(const std::vector<Candidate>& candidates,
                                       const std::vector<Eigen::Isometry3d>& estimate, const RegistrationInputs& inputs,
                                       const PipelineConfig& config, const Plan& plan, const std::atomic<bool>* cancel);

}  // namespace bathyslam
