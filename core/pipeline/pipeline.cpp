#include "core/pipeline/pipeline.h"

#include <algorithm>
#include <chrono>
#include <limits>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <opencv2/imgproc.hpp>

#include "core/fuse/difference.h"
#include "core/parallel/parallel_for.h"
#include "core/pipeline/register_pairs.h"
#include "core/pipeline/robust_backend.h"
#include "core/types/survey_starts.h"

namespace bathyslam {
namespace {

// Submaps prepared for our GICP kept between batches (~1.4 MB each): `lake` (~490 MB) keeps
// nearly all; `large` keeps the last 3-4 lines', which its next adjacent pairs reuse, instead of
// growing by the whole survey. On `large` half a GiB prepares 2 % more submaps again than 1 GiB
// and lowers the peak by half a GiB (docs/performance.md).
constexpr std::size_t kPreparedSubmapsBudgetBytes = std::size_t{512} << 20;

// The register stage frees ~1.5 GB on `large` (prepared submaps, features) in pieces the allocator
// keeps for reuse, but the map made next needs pieces of other sizes: without this, a process's
// peak is the register stage's memory plus the map's (docs/performance.md).
void return_freed_memory() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

class StageClock {
 public:
  StageClock(std::vector<StageTiming>& timings, std::chrono::steady_clock::time_point start)
      : timings_(timings), start_(start) {}
  void done(const std::string& stage) {
    const auto now = std::chrono::steady_clock::now();
    timings_.push_back({stage, std::chrono::duration<double>(now - start_).count()});
    start_ = now;
  }

 private:
  std::vector<StageTiming>& timings_;
  std::chrono::steady_clock::time_point start_;
};

std::vector<Cloud::Ptr> filtered_clouds(const SubmapSet& submaps, const VoxelConfig& voxel, const Plan& plan,
                                        const std::atomic<bool>* cancel) {
  std::vector<Cloud::Ptr> clouds(submaps.submaps.size());
  parallel_for(clouds.size(), plan.threads, cancel,
               [&](std::size_t i) { clouds[i] = voxel_filter(submaps.submaps[i].points, voxel); }, 4);
  return clouds;
}

std::vector<SubmapFeatures> submap_features(const SubmapSet& submaps, const PipelineConfig& config, const Plan& plan,
                                            const std::atomic<bool>* cancel) {
  std::vector<SubmapFeatures> features(submaps.submaps.size());
  parallel_for(features.size(), plan.threads, cancel,
               [&](std::size_t i) { features[i] = extract_features(submaps.submaps[i], config.grid, config.keypoints); }, 4);
  return features;
}

// The candidates whose later submap lies in [begin, end), with footprints at `estimate`.
std::vector<Candidate> candidates_ending_in(const SubmapSet& submaps, const std::vector<Eigen::Isometry3d>& estimate,
                                            int begin, int end, const CandidateConfig& config, const Plan& plan) {
  std::vector<Candidate> candidates;
  auto take = [&](const std::vector<CandidatePair>& found, ConstraintType type) {
    for (const CandidatePair& p : found) candidates.push_back({p, type});
  };
  const LaterSubmaps batch{begin, end};
  take(adjacent_line_candidates(submaps, estimate, config, batch), ConstraintType::kAdjacent);
  if (plan.loop_closures) take(loop_candidates(submaps, estimate, config, batch), ConstraintType::kLoop);
  return candidates;
}

// The first submap an edge touches that entered or left the graph since the last solve, whose
// graph `solved_with` records (then updated to the graph now); INT_MAX when none did.
int first_node_changed(const std::vector<Constraint>& constraints, std::vector<char>& solved_with) {
  int first = std::numeric_limits<int>::max();
  solved_with.resize(constraints.size(), 0);
  for (std::size_t k = 0; k < constraints.size(); ++k) {
    const char now = constraints[k].in_graph();
    if (now == solved_with[k]) continue;
    first = std::min({first, constraints[k].from, constraints[k].to});
    solved_with[k] = now;
  }
  return first;
}

// The registrations so far as observations of dead reckoning's drift: every one the
// registration tests accepted whose horizontal answer is the terrain's (unique within the
// probe's reach and reached from other starts too, or doubted and widened by where the other
// starts landed: widened_by_doubt), whatever the prior's gates said of it (they rest on the noise
// being estimated). An ambiguous answer with its own tight information stays out: counted, it
// would say dead reckoning is right (on sand waves the heading noise came out 6 to 11 times too
// small, even with its aliases as a wrapped likelihood) and the gates built on that would rule
// out the true alignment. Nor does an alias's scatter count as a registration's noise: it is a
// bound on where the answer may be, and counted as noise it made every sand-wave survey's
// navigation look perfect. A registration across two surveys observes their start fixes too,
// whose noise is not estimated: it stays out.
bool observes_drift(const Constraint& c, const Plan& plan, const GraphConfig& graph) {
  if (from_navigation(c.type) || (c.rejection.rejected() && !refused_by_prior(c.rejection, plan))) return false;
  if (!graph.same_survey(c.from, c.to)) return false;
  if (!carries_horizontal_information(c.registered_information)) return false;
  const bool widened = c.horizontal_spread.trace() > 0;
  return widened || (c.uniqueness.unique() && c.horizontal_doubt.empty());
}

std::vector<DrInnovation> dr_innovations(const std::vector<Constraint>& constraints, const DrNoiseModel& dr,
                                         const std::vector<Eigen::Isometry3d>& dr_poses, const Plan& plan,
                                         const GraphConfig& graph) {
  std::vector<DrInnovation> innovations;
  for (const Constraint& c : constraints) {
    if (!observes_drift(c, plan, graph)) continue;
    innovations.push_back(dr_innovation({c.from, c.to, c.measured, c.registered_information, true, c.anchor}, dr, dr_poses));
  }
  return innovations;
}

// The register stage's answer.
struct Registrations {
  std::vector<Constraint> constraints;  // dead reckoning's odometry first, then every registration
  // The survey's own DR noise (navigation_noise.h), which the graph's odometry edges, the gates
  // and the safety net use; the prior's when not estimated.
  NavigationNoiseEstimate navigation_noise;
  int batch_solves = 0;  // the graph solves between batches, and their time
  double batch_solve_seconds = 0;
  int batches = 0, batches_taken_up = 0;  // of them, registered by an earlier run (checkpoints)
};

// Estimates the survey's DR noise from the registrations so far when they have grown by a
// quarter since the last estimate (or `last`), and, when the model changes, gives the odometry
// edges its information and judges every registration again under it (judge_with_prior).
class NavigationNoiseTracker {
 public:
  explicit NavigationNoiseTracker(const PipelineConfig& config) : config_(config) {}

  void update(Registrations& r, const std::vector<Eigen::Isometry3d>& dr_poses, DrNoiseModel& dr, DrNoiseModel& alias_dr,
              KnownConflicts& known_conflicts, const Plan& plan, bool last) {
    // Counted first: the innovations themselves are built only when an estimate is due.
    const auto count = static_cast<double>(std::count_if(r.constraints.begin(), r.constraints.end(),
                                                         [&](const Constraint& c) { return observes_drift(c, plan, config_.graph); }));
    if (count < config_.navigation_noise.min_registrations || (!last && count < 1.25 * estimated_from_)) return;
    if (count == estimated_from_) return;
    estimated_from_ = count;
    r.navigation_noise = estimate_navigation_noise(dr_poses, dr_innovations(r.constraints, dr, dr_poses, plan, config_.graph),
                                                   config_.graph, config_.navigation_noise, r.navigation_noise.heading_steps);
    const GraphConfig& graph = r.navigation_noise.graph;
    dr = DrNoiseModel(dr_poses, graph);
    alias_dr = DrNoiseModel(dr_poses, alias_graph(r.navigation_noise, config_.navigation_noise));
    known_conflicts = KnownConflicts{};  // PCM's tests rest on the model
    for (Constraint& c : r.constraints) {
      if (c.type == ConstraintType::kOdometry) {
        c.information = odometry_information(graph, c.from);
      } else {
        judge_with_prior(c, dr, alias_dr, dr_poses, config_, plan);
      }
    }
  }

 private:
  const PipelineConfig& config_;
  double estimated_from_ = 0;  // innovations at the last estimate
};

// The batch [begin, end) as an earlier run of the job registered it, when it registered these
// very candidates from these very guesses (the same pairs in the same order, each guess equal to
// the last bit: the run before was this run, up to here); nullptr otherwise.
const RegisteredBatch* taken_up(const RegistrationCheckpoints* checkpoints, int begin, int end,
                                const std::vector<Candidate>& candidates, const std::vector<Eigen::Isometry3d>& estimate) {
  if (!checkpoints) return nullptr;
  const auto same = [&](const Constraint& c, const Candidate& candidate) {
    const CandidatePair& pair = candidate.pair;
    return c.type == candidate.type && c.from == pair.target && c.to == pair.source &&
           c.guess.matrix() == (estimate[pair.target].inverse() * estimate[pair.source]).matrix();
  };
  for (const RegisteredBatch& stored : checkpoints->stored) {
    if (stored.begin == begin && stored.end == end &&
        std::equal(stored.constraints.begin(), stored.constraints.end(), candidates.begin(), candidates.end(), same))
      return &stored;
  }
  return nullptr;
}

// Where dead reckoning leaves a registration's competitors open, the graph kept so far may not
// (robustness.alias_from_graph). Each registration from `batch_first` on that dead reckoning left
// so is judged again against where that graph puts its two submaps (graph_alias_gate: the batch's
// estimate, the graph's covariance of the pair); where the verdict keeps more, PCM selects again
// and the graph is solved with it (not before `first_free`), and the rest are judged again, at
// most alias_graph_rounds times: on a lawnmower the pairs next to one that now holds are a
// submap's odometry away from it, where the pairs beyond the turn were a whole line's.
void judge_aliases_by_graph(Registrations& r, std::size_t batch_first, int end, int first_free,
                            std::vector<Eigen::Isometry3d>& estimate, const DrNoiseModel& dr, const DrNoiseModel& alias_dr,
                            const std::vector<Eigen::Isometry3d>& dr_poses, const PipelineConfig& config, const Plan& plan,
                            KnownConflicts* known) {
  std::vector<std::size_t> open;
  for (std::size_t k = batch_first; k < r.constraints.size(); ++k) {
    const Constraint& c = r.constraints[k];
    // Adjacent pairs only: a loop spans a long chain whose covariance in the graph rests on the
    // survey's noise estimate (at its lower bound on sand waves), and on the `small` matrix loops
    // judged so were kept 2-7 m off within sigmas under 2 m (docs/slam-every-seabed.md).
    if (c.type == ConstraintType::kAdjacent && c.in_graph() && c.alias == AliasResolution::kInformationRemoved &&
        c.uniqueness.probed)
      open.push_back(k);
  }
  for (int round = 0; round < config.robustness.alias_graph_rounds && !open.empty(); ++round) {
    std::vector<PoseGraphEdge> edges;
    for (const Constraint& c : r.constraints) {
      if (c.in_graph() && c.from < end && c.to < end) edges.push_back(graph_edge(c));
    }
    std::vector<std::pair<int, int>> pairs;
    for (std::size_t k : open) pairs.emplace_back(r.constraints[k].from, r.constraints[k].to);
    const auto covariances = relative_covariances(estimate, edges, r.navigation_noise.graph, pairs);
    if (!covariances) break;
    std::vector<std::size_t> still_open;
    int first_gained = std::numeric_limits<int>::max();
    for (std::size_t i = 0; i < open.size(); ++i) {
      Constraint& c = r.constraints[open[i]];
      const Information6 before = c.information;
      const AliasGate gate = graph_alias_gate(c, estimate, (*covariances)[i].topLeftCorner<2, 2>());
      judge_with_prior(c, dr, alias_dr, dr_poses, config, plan, &gate);
      if (c.in_graph() && (c.information - before).topLeftCorner<2, 2>().squaredNorm() > 0) {
        first_gained = std::min({first_gained, c.from, c.to});
      } else if (c.in_graph()) {
        still_open.push_back(open[i]);
      }
    }
    open = std::move(still_open);
    if (first_gained == std::numeric_limits<int>::max()) break;
    if (plan.consistency) select_consistent_registrations(r.constraints, dr, dr_poses, config.robustness.pcm, known);
    estimate = solve(estimate, r.constraints, r.navigation_noise.graph, end, std::max(first_gained, first_free)).poses;
  }
}

// Registration in survey order, a batch of submaps at a time, as a vehicle would map: each
// batch is predicted by dead reckoning from the trajectory corrected so far, its candidates are
// registered from that prediction, and the graph is solved before the next batch. A pair's
// guess then carries the drift of one batch rather than of everything between its two
// submaps, which across a lawnmower is tens of metres, far outside GICP's basin. Without
// batches, one batch of every submap: every guess straight from dead reckoning. `r` holds dead
// reckoning's odometry and the prior's noise when it starts.
Registrations register_incrementally(Registrations r, const SubmapSet& submaps, const RegistrationInputs& inputs,
                                     DrNoiseModel& dr, DrNoiseModel& alias_dr, const PipelineConfig& config, const Plan& plan,
                                     const ProgressFn& progress, const std::atomic<bool>* cancel,
                                     const RegistrationCheckpoints* checkpoints) {
  const std::vector<Eigen::Isometry3d>& dr_poses = inputs.dr_poses;
  NavigationNoiseTracker noise(config);
  const int n = static_cast<int>(dr_poses.size());
  const int batch = plan.batch_submaps > 0 ? plan.batch_submaps : std::max(n, 1);
  std::vector<Eigen::Isometry3d> estimate = dr_poses;
  std::vector<char> solved_with;  // per constraint: in the graph at the last solve
  KnownConflicts known_conflicts;  // PCM's pairwise tests so far, by constraint
  for (int begin = 0; begin < n; begin += batch) {
    const int end = std::min(n, begin + batch);
    for (int s = std::max(begin, 1); s < end; ++s) {
      // Another survey's start is predicted from the datum, as its navigation placed it.
      const int previous = config.graph.has_step(s - 1) ? s - 1 : 0;
      estimate[s] = estimate[previous] * (dr_poses[previous].inverse() * dr_poses[s]);
    }
    const std::vector<Candidate> candidates = candidates_ending_in(submaps, estimate, begin, end, config.candidates, plan);
    ++r.batches;
    throw_if_cancelled(cancel);  // a batch taken up registers nothing, where the cancel is seen
    const std::size_t batch_first = r.constraints.size();
    if (const RegisteredBatch* stored = taken_up(checkpoints, begin, end, candidates, estimate)) {
      r.constraints.insert(r.constraints.end(), stored->constraints.begin(), stored->constraints.end());
      ++r.batches_taken_up;
    } else {
      RegisteredBatch registered{begin, end, register_pairs(candidates, estimate, inputs, config, plan, cancel)};
      if (checkpoints && checkpoints->keep) checkpoints->keep(registered);
      r.constraints.insert(r.constraints.end(), registered.constraints.begin(), registered.constraints.end());
    }
    inputs.prepared.trim(kPreparedSubmapsBudgetBytes);
    if (plan.estimate_noise) noise.update(r, dr_poses, dr, alias_dr, known_conflicts, plan, end == n);
    if (plan.consistency) {
      select_consistent_registrations(r.constraints, dr, dr_poses, config.robustness.pcm, &known_conflicts);
    }
    const int survey_begin = survey_nodes(config.graph.survey_starts, survey_of(config.graph.survey_starts, begin), n).begin;
    if (plan.alias_from_graph) {
      const auto start = std::chrono::steady_clock::now();
      judge_aliases_by_graph(r, batch_first, end, survey_begin, estimate, dr, alias_dr, dr_poses, config, plan,
                             &known_conflicts);
      r.batch_solve_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    const int first_changed = first_node_changed(r.constraints, solved_with);
    if (end < n && first_changed < end) {
      // The submaps registered so far: the later ones would hang off them by odometry alone and
      // move along without bending anything, so the solve grows with the survey mapped so far
      // instead of being the whole survey's 290 times over. And only
      // from the first submap a registration entering or leaving the graph touches: the earlier
      // ones stay where the last solve put them (the final solve moves everything), or else the
      // solves grow with the square of the survey (both measured on `large`: docs/performance.md).
      // Of several surveys, the earlier ones are held too: the batch is mapped against them, and
      // a registration with an early submap of the first survey would otherwise re-solve every
      // survey each batch (20 `small` surveys: 358 of 628 s). The final solve moves them all.
      const auto start = std::chrono::steady_clock::now();
      estimate = solve(estimate, r.constraints, r.navigation_noise.graph, end, std::max(first_changed, survey_begin)).poses;
      r.batch_solve_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      ++r.batch_solves;
    }
    if (progress) progress("register", static_cast<double>(end) / n);
  }
  return r;
}

std::vector<int> line_of_node(const SubmapSet& submaps) {
  std::vector<int> lines;
  for (const Submap& s : submaps.submaps) lines.push_back(s.line);
  return lines;
}

// The graph solved, through the safety net where the plan has it.
Publication solve_graph(const SubmapSet& submaps, const std::vector<Eigen::Isometry3d>& dr_poses,
                        std::vector<Constraint>& constraints, const GraphConfig& graph, const PipelineConfig& config,
                        const Plan& plan) {
  if (plan.safety_net) return solve_with_safety_net(dr_poses, line_of_node(submaps), constraints, graph, config.robustness);
  return {solve(dr_poses, constraints, graph), {}};
}

// How the published map compares with dead reckoning's and with the reference.
struct Evaluation {
  ConsistencyReport dr_consistency, consistency;
  std::optional<SiteConsistency> dr_site_consistency, site_consistency;
  std::vector<double> dr_trajectory_errors, trajectory_errors;
  std::vector<double> dr_aligned_trajectory_errors, aligned_trajectory_errors;
};

// Evaluates the solution `published`; with the safety net, a solved map less consistent than dead
// reckoning's is not published: dead reckoning is, and evaluated instead.
Evaluation evaluate(const SubmapSet& submaps, const std::vector<Eigen::Isometry3d>& dr_poses, Publication& published,
                    std::vector<Constraint>& constraints, const PipelineConfig& config, const Plan& plan) {
  Evaluation e;
  e.dr_consistency = consistency_error(submaps, dr_poses, config.consistency);
  e.consistency = consistency_error(submaps, published.graph.poses, config.consistency);
  if (plan.safety_net && !published.safety_net.fell_back) {
    fall_back_unless_more_consistent(published, e.consistency, e.dr_consistency, submaps, dr_poses, constraints, config);
  }
  const std::vector<Eigen::Isometry3d>& poses = published.graph.poses;
  if (!submaps.survey_starts.empty()) {
    e.dr_site_consistency = site_consistency(submaps, dr_poses, config.consistency);
    e.site_consistency = site_consistency(submaps, poses, config.consistency);
  }
  e.dr_trajectory_errors = trajectory_errors(submaps, dr_poses);
  e.trajectory_errors = trajectory_errors(submaps, poses);
  e.dr_aligned_trajectory_errors = aligned_trajectory_errors(submaps, dr_poses);
  e.aligned_trajectory_errors = aligned_trajectory_errors(submaps, poses);
  return e;
}

// The published solution and its evaluation into the result.
void take_publication(PipelineResult& r, Publication published, Evaluation evaluated) {
  r.graph = std::move(published.graph);
  r.safety_net = std::move(published.safety_net);
  r.optimized_poses = r.graph.poses;
  r.dr_consistency = std::move(evaluated.dr_consistency);
  r.consistency = std::move(evaluated.consistency);
  r.dr_site_consistency = std::move(evaluated.dr_site_consistency);
  r.site_consistency = std::move(evaluated.site_consistency);
  r.dr_trajectory_errors = std::move(evaluated.dr_trajectory_errors);
  r.trajectory_errors = std::move(evaluated.trajectory_errors);
  r.dr_aligned_trajectory_errors = std::move(evaluated.dr_aligned_trajectory_errors);
  r.aligned_trajectory_errors = std::move(evaluated.aligned_trajectory_errors);
}

// `built_since`: when the making of `built` began, for the "submaps" stage's time. Each stage
// returns its answer; the result is assembled from them at the end.
PipelineResult run(SubmapSet built, std::chrono::steady_clock::time_point built_since, const PipelineConfig& given,
                   const ProgressFn& progress, const std::atomic<bool>* cancel,
                   const RegistrationCheckpoints* checkpoints) {
  auto report = [&](std::string_view stage, double fraction) {
    if (progress) progress(stage, fraction);
  };
  const double scale = footprint_scale(built.footprint, given);
  PipelineConfig config = scaled_to_footprint(given, scale);
  config.graph.survey_starts = built.survey_starts;
  const Plan plan = plan_of(config);
  std::vector<StageTiming> timings;
  StageClock clock(timings, built_since);

  const SubmapSet& submaps = built;
  std::vector<Eigen::Isometry3d> dr_poses;
  for (const Submap& s : submaps.submaps) dr_poses.push_back(s.dr_pose);
  Registrations registered{odometry_constraints(dr_poses, config.graph), {}};
  registered.navigation_noise.graph = config.graph;
  clock.done("submaps");
  report("submaps", 1);
  throw_if_cancelled(cancel);

  if (plan.registration) {
    // PCL's GICP registers on the filtered clouds, all made first. Ours registers on submaps the
    // cache prepares from them on first use, filtering each then: `large`'s filtered clouds
    // would not fit beside its submaps.
    std::vector<Cloud::Ptr> clouds;
    if (!plan.own_gicp) {
      report("filter", 0);
      clouds = filtered_clouds(submaps, config.voxel, plan, cancel);
      clock.done("filter");
    }

    std::vector<SubmapFeatures> features;
    if (plan.features) {
      report("features", 0);
      features = submap_features(submaps, config, plan, cancel);
      clock.done("features");
    }

    report("register", 0);
    // The survey's estimate replaces them as registrations come (navigation_noise.h: the loosest
    // heading it does not rule out, and for the aliases alias_graph's).
    DrNoiseModel dr(dr_poses, config.graph), alias_dr(dr_poses, config.graph);
    // Only ours asks the cache for a submap (prepared_pair): it filters each on first use.
    const auto filtered = [&](std::size_t i) -> Cloud::ConstPtr {
      return voxel_filter(submaps.submaps[i].points, config.voxel);
    };
    GicpCloudCache prepared(submaps.submaps.size(), filtered, config.registration.gicp);
    registered = register_incrementally(std::move(registered), submaps,
                                        {clouds, prepared, features, dr_poses, dr, alias_dr}, dr, alias_dr, config, plan,
                                        progress, cancel, checkpoints);
  }  // freeing the clouds, features and prepared submaps is the register stage's time, not the graph's
  if (plan.registration) {
    return_freed_memory();
    clock.done("register");
  }

  report("graph", 0);
  Publication published =
      solve_graph(submaps, dr_poses, registered.constraints, registered.navigation_noise.graph, config, plan);
  clock.done("graph");
  throw_if_cancelled(cancel);

  report("eval", 0);
  Evaluation evaluated = evaluate(submaps, dr_poses, published, registered.constraints, config, plan);
  clock.done("eval");
  report("done", 1);

  PipelineResult r;
  r.config = std::move(config);
  r.footprint_scale = scale;
  r.submaps = std::move(built);
  r.dr_poses = std::move(dr_poses);
  r.constraints = std::move(registered.constraints);
  r.navigation_noise = std::move(registered.navigation_noise);
  r.batch_solves = registered.batch_solves;
  r.batch_solve_seconds = registered.batch_solve_seconds;
  r.batches = registered.batches;
  r.batches_taken_up = registered.batches_taken_up;
  take_publication(r, std::move(published), std::move(evaluated));
  r.timings = std::move(timings);
  return r;
}

// The change of `map` where it is significant, 0 where it is not, NaN off the map.
double significant_change(const DifferenceMap& map, std::int64_t col, std::int64_t row) {
  if (!map.geometry.contains(col, row)) return NAN;
  const std::size_t i = map.geometry.index(col, row);
  return map.significant[i] == 1.0f ? map.change[i] : std::isnan(map.change[i]) ? NAN : 0.0;
}

// What the significant change since the first survey shifts the overlap of a registration's two
// submaps by (at the solution): its mean over the overlap's cells, the share of the change a
// least-squares registration takes for a misfit. NaN when the overlap has no cell of both.
double change_over_overlap(const PipelineResult& r, const Constraint& c, const DifferenceMap& later,
                           const DifferenceMap* earlier) {
  const FootprintOverlap shared = footprint_overlap(footprint_of(r.submaps.submaps[c.from], r.optimized_poses[c.from]),
                                                    footprint_of(r.submaps.submaps[c.to], r.optimized_poses[c.to]));
  if (shared.area_m2 <= 0) return NAN;
  std::vector<cv::Point2f> overlap;  // the float corners OpenCV gave, exactly
  for (const Eigen::Vector2d& p : shared.polygon) overlap.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()));
  const cv::Rect box = cv::boundingRect(overlap);
  const GridGeometry& g = later.geometry;
  const double res = g.resolution_m, e0 = r.submaps.origin.easting, n0 = r.submaps.origin.northing;
  double sum = 0;
  int cells = 0;
  for (std::int64_t col = g.col_of(e0 + box.x); col <= g.col_of(e0 + box.br().x); ++col) {
    for (std::int64_t row = g.row_of(n0 + box.y); row <= g.row_of(n0 + box.br().y); ++row) {
      const cv::Point2f centre(static_cast<float>((col + 0.5) * res - e0), static_cast<float>((row + 0.5) * res - n0));
      if (cv::pointPolygonTest(overlap, centre, false) < 0) continue;
      const double change = significant_change(later, col, row) - (earlier ? significant_change(*earlier, col, row) : 0.0);
      if (std::isnan(change)) continue;
      sum += change;
      ++cells;
    }
  }
  return cells > 0 ? sum / cells : NAN;
}

}  // namespace

int discount_change_across_surveys(PipelineResult& r, const FuseConfig& fuse, const DifferenceConfig& difference) {
  const std::vector<int>& starts = r.submaps.survey_starts;
  if (starts.empty() || r.safety_net.fell_back) return 0;
  const auto start = std::chrono::steady_clock::now();
  const GridRaster first = fuse_survey(r.submaps, r.optimized_poses, 0, fuse);
  std::vector<DifferenceMap> since_first(starts.size() + 1);
  for (std::size_t k = 1; k < since_first.size(); ++k) {
    since_first[k] = difference_map(first, fuse_survey(r.submaps, r.optimized_poses, static_cast<int>(k), fuse), difference);
  }
  int doubted = 0;
  for (Constraint& c : r.constraints) {
    if (!c.in_graph() || from_navigation(c.type)) continue;
    int a = survey_of(starts, c.from), b = survey_of(starts, c.to);
    if (a == b) continue;
    if (a > b) std::swap(a, b);
    const double sigma = std::max(since_first[b].sigma_vertical_m, a > 0 ? since_first[a].sigma_vertical_m : 0.0);
    const double shift = change_over_overlap(r, c, since_first[b], a > 0 ? &since_first[a] : nullptr);
    if (std::isnan(shift) || std::abs(shift) <= sigma) continue;
    for (int k : {2, 3, 4}) c.information.row(k).setZero(), c.information.col(k).setZero();
    ++doubted;
  }
  r.registrations_over_change = doubted;
  if (doubted > 0) {
    // Solved as run() solves: with the safety net only where the configuration has it. Its drops
    // of the first solve stay out of the graph; the verdict counts both solves' drops.
    const Plan plan = plan_of(r.config);
    Publication published = solve_graph(r.submaps, r.dr_poses, r.constraints, r.navigation_noise.graph, r.config, plan);
    if (plan.safety_net) count_earlier_drops(published.safety_net, r.safety_net);
    Evaluation evaluated = evaluate(r.submaps, r.dr_poses, published, r.constraints, r.config, plan);
    take_publication(r, std::move(published), std::move(evaluated));
  }
  // Consistency across the surveys where the seabed did not change.
  const auto changed = [&](const Eigen::Vector2d& p) {
    const double easting = r.submaps.origin.easting + p.x(), northing = r.submaps.origin.northing + p.y();
    return std::any_of(since_first.begin() + 1, since_first.end(), [&](const DifferenceMap& map) {
      const GridGeometry& g = map.geometry;
      const std::int64_t col = g.col_of(easting), row = g.row_of(northing);
      return g.contains(col, row) && map.significant[g.index(col, row)] == 1.0f;
    });
  };
  if (!r.safety_net.fell_back) {
    r.site_consistency = site_consistency(r.submaps, r.optimized_poses, r.config.consistency, changed);
    r.dr_site_consistency = site_consistency(r.submaps, r.dr_poses, r.config.consistency, changed);
    r.across_where_unchanged = true;
  }
  r.timings.push_back({"change", std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()});
  return doubted;
}

PipelineResult run_pipeline(const Survey& survey, const PipelineConfig& config, const ProgressFn& progress,
                            const std::atomic<bool>* cancel) {
  const auto start = std::chrono::steady_clock::now();
  if (progress) progress("submaps", 0);
  return run(build_submaps(survey, config.submaps), start, config, progress, cancel, nullptr);
}

PipelineResult run_pipeline(SubmapSet submaps, double submaps_seconds, const PipelineConfig& config,
                            const ProgressFn& progress, const std::atomic<bool>* cancel,
                            const RegistrationCheckpoints* checkpoints) {
  const auto built_since = std::chrono::steady_clock::now() -
                           std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                               std::chrono::duration<double>(submaps_seconds));
  return run(std::move(submaps), built_since, config, progress, cancel, checkpoints);
}

}  // namespace bathyslam
