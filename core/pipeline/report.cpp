#include "core/pipeline/report.h"

#include <cstdio>
#include <optional>

#include "core/eval/plots.h"
#include "core/io/file_bytes.h"
#include "core/types/format.h"

namespace bathyslam {
namespace {

// Null for no values: a figure over nothing is not zero, and a reader must not take it for one.
nlohmann::json stats_json(const ErrorStats& s) {
  if (s.count == 0) return nullptr;
  return {{"rmse", s.rmse}, {"mean", s.mean}, {"std", s.std}, {"p50", s.p50}, {"p95", s.p95},
          {"p99", s.p99},   {"max", s.max},   {"count", s.count}};
}

// The switch's decision without its numbers ("too few features (density 0.002 < 0.005)" ->
// "too few features"), for counting.
std::string kind_of(const std::string& reason) {
  std::string kind = reason.substr(0, reason.find_first_of("0123456789("));
  while (!kind.empty() && kind.back() == ' ') kind.pop_back();
  return kind;
}

nlohmann::json counts_json(const std::map<std::string, ConstraintCounts>& groups) {
  nlohmann::json out = nlohmann::json::object();
  for (const auto& [name, c] : groups) {
    out[name] = {{"candidates", c.candidates}, {"accepted", c.accepted}, {"rejected", c.rejected},
                 {"rejection_reasons", c.rejections}};
  }
  return out;
}

// How the switch decided, by path: its reasons without their numbers.
nlohmann::json switch_decisions(const PipelineResult& r) {
  nlohmann::json decisions = nlohmann::json::object();
  for (const Constraint& c : r.constraints) {
    if (!c.path || c.path_reason.empty()) continue;
    nlohmann::json& d = decisions[to_string(*c.path)];
    if (d.is_null()) d = nlohmann::json::object();
    d[kind_of(c.path_reason)] = d.value(kind_of(c.path_reason), 0) + 1;
  }
  return decisions;
}

ErrorStats stats_from_json(const nlohmann::json& j) {
  ErrorStats s;
  if (j.is_null()) return s;  // not computed (stats_json)
  s.rmse = j.at("rmse").get<double>();
  s.mean = j.at("mean").get<double>();
  s.std = j.at("std").get<double>();
  s.p50 = j.at("p50").get<double>();
  s.p95 = j.at("p95").get<double>();
  s.p99 = j.at("p99").get<double>();
  s.max = j.at("max").get<double>();
  s.count = j.at("count").get<std::size_t>();
  return s;
}

std::map<std::string, ConstraintCounts> counts_from_json(const nlohmann::json& j) {
  std::map<std::string, ConstraintCounts> groups;
  for (const auto& [name, c] : j.items()) {
    ConstraintCounts& out = groups[name];
    out.candidates = c.at("candidates").get<std::int64_t>();
    out.accepted = c.at("accepted").get<std::int64_t>();
    out.rejected = c.at("rejected").get<std::int64_t>();
    out.rejections = c.at("rejection_reasons").get<std::map<std::string, std::int64_t>>();
  }
  return groups;
}

// Every registration with its quality, and its error against the reference where there is one.
nlohmann::json registrations_json(const PipelineResult& r) {
  nlohmann::json list = nlohmann::json::array();
  for (const Constraint& c : r.constraints) {
    if (from_navigation(c.type)) continue;
    nlohmann::json j = {{"type", to_string(c.type)},
                        {"from", c.from},
                        {"to", c.to},
                        {"overlap_fraction", c.overlap_fraction},
                        {"converged", c.quality.converged},
                        {"fitness", c.quality.fitness},
                        {"overlap_points", c.quality.overlap_points},
                        {"overlap_mse_m2", c.quality.overlap_mse_m2},
                        {"path", c.path ? to_string(*c.path) : ""},
                        {"path_reason", c.path_reason},
                        {"feature_density", c.feature_density},
                        {"matches", c.matches},
                        {"inlier_ratio", c.inlier_ratio},
                        // In the graph: passed every registration test and kept by the back end.
                        {"accepted", c.in_graph()},
                        {"rejection", to_string(c.why_not().kind)},
                        {"reason", c.why_not().text()}};
    nlohmann::json gates = nlohmann::json::object();
    if (c.dr_mahalanobis2 >= 0) {
      gates["dr_mahalanobis2"] = c.dr_mahalanobis2;
      gates["dr_threshold"] = r.config.robustness.pcm.plausibility.chi2_threshold;
    }
    if (!c.horizontal_doubt.empty()) gates["horizontal_doubt"] = c.horizontal_doubt;
    if (c.path == RegistrationPath::kFeatureAided) {
      gates["competitor_inliers"] = c.competitor_inliers;
      gates["competitor_separation_m"] = c.competitor_separation_m;
    }
    if (c.uniqueness.probed) {
      gates["local_cost_m2"] = c.uniqueness.local_cost_m2;
      gates["distinctness"] = c.uniqueness.distinctness();
      gates["alternative_offset_m"] = {c.uniqueness.alternative_offset_m.x(), c.uniqueness.alternative_offset_m.y()};
      gates["cost_at_answer_m2"] = c.uniqueness.cost_at_answer_m2;
      gates["alternative_cost_m2"] = c.uniqueness.alternative_cost_m2;
      gates["typical_cost_m2"] = c.uniqueness.typical_cost_m2;
      if (c.alias != AliasResolution::kNone) {
        gates["alias"] = to_string(c.alias);
        gates["alias_dr_mahalanobis2"] = c.alias_mahalanobis2;
        if (c.alias == AliasResolution::kInformationRemoved) gates["alias_spread_m"] = {c.alias_spread_m.x(), c.alias_spread_m.y()};
      }
    }
    j["gates"] = gates;
    auto error_json = [&](const Eigen::Isometry3d& measured) -> nlohmann::json {
      const auto e = relative_pose_error(r.submaps, c.from, c.to, measured);
      if (!e) return nullptr;
      return {{"translation_m", e->translation_m}, {"horizontal_m", e->horizontal_m}, {"yaw_deg", e->yaw_deg}};
    };
    // Enough to rebuild the edge without registering again (bench/regraph.cpp re-weighs them).
    const Eigen::Quaterniond q(c.measured.rotation());
    j["measured"] = {{"translation_m", {c.measured.translation().x(), c.measured.translation().y(), c.measured.translation().z()}},
                     {"rotation_wxyz", {q.w(), q.x(), q.y(), q.z()}}};
    j["anchor_m"] = {c.anchor.x(), c.anchor.y(), c.anchor.z()};
    if (c.in_graph()) {
      const Eigen::Matrix<double, 6, 1> d = c.information.diagonal();
      j["information_diagonal"] = std::vector<double>(d.data(), d.data() + 6);
      j["information"] = std::vector<double>(c.information.data(), c.information.data() + 36);  // symmetric
    }
    if (nlohmann::json e = error_json(c.measured); !e.is_null()) {
      j["error_vs_reference"] = e;
      j["guess_error_vs_reference"] = error_json(c.guess);
      if (c.in_graph()) {
        const auto sigmas = edge_error_sigmas(r.submaps, c.from, c.to, c.measured, c.anchor, c.information);
        j["error_sigmas"] = {{"horizontal", sigmas->horizontal}, {"yaw", sigmas->yaw}, {"joint", sigmas->joint},
                             {"error_at_anchor_m", {sigmas->at_anchor_m.x(), sigmas->at_anchor_m.y()}}};
      }
    }
    list.push_back(std::move(j));
  }
  return list;
}

nlohmann::json safety_net_json(const SafetyNet& net) {
  if (!net.ran) return {{"verdict", "not run"}};
  nlohmann::json lines = nlohmann::json::array();
  for (const LineCheck& l : net.check.lines) {
    lines.push_back({{"line", l.run.line}, {"first_submap", l.run.first}, {"last_submap", l.run.last}, {"chi2", l.chi2},
                     {"dof", l.dof}, {"threshold", l.threshold}, {"pass", l.pass}});
  }
  return {{"verdict", net.verdict}, {"pass", net.pass}, {"fell_back_to_dead_reckoning", net.fell_back},
          {"dropped", net.dropped}, {"lines", lines}};
}

}  // namespace

std::optional<std::string> trajectory_not_computed(const PipelineResult& r) {
  if (!r.dr_trajectory_errors.empty()) return std::nullopt;
  return std::string("no reference navigation");
}

std::optional<std::string> consistency_not_computed(const PipelineResult& r) {
  if (r.dr_consistency.stats.count > 0) return std::nullopt;
  return format("no map cell seen by two survey lines (%zu lines, %.2f m cells)", r.submaps.lines.size(),
                r.config.consistency.cell_m);
}

ReportSummary report_summary(const PipelineResult& r) {
  ReportSummary s;
  s.configuration = to_string(r.config.configuration);
  s.trajectory = error_stats(r.trajectory_errors);
  s.trajectory_dr = error_stats(r.dr_trajectory_errors);
  s.consistency = r.consistency.stats;
  s.consistency_dr = r.dr_consistency.stats;
  s.histogram = r.consistency.histogram;
  auto count = [](ConstraintCounts& t, const Constraint& c) {
    ++t.candidates;
    if (c.in_graph()) {
      ++t.accepted;
    } else {
      ++t.rejected;
      ++t.rejections[to_string(c.why_not().kind)];
    }
  };
  for (const Constraint& c : r.constraints) {
    count(s.by_type[to_string(c.type)], c);
    if (c.path) count(s.by_path[to_string(*c.path)], c);
  }
  return s;
}

ReportSummary report_summary_from_json(const nlohmann::json& j) {
  try {
    ReportSummary s;
    s.configuration = j.at("configuration").get<std::string>();
    const nlohmann::json& trajectory = j.at("trajectory_error_m");
    s.trajectory = stats_from_json(trajectory.at("optimized"));
    s.trajectory_dr = stats_from_json(trajectory.at("dead_reckoning"));
    const nlohmann::json& consistency = j.at("consistency_error_m");
    s.consistency = stats_from_json(consistency.at("optimized"));
    s.consistency_dr = stats_from_json(consistency.at("dead_reckoning"));
    s.histogram.bin_width = consistency.at("histogram").at("bin_width_m").get<double>();
    s.histogram.counts = consistency.at("histogram").at("counts").get<std::vector<std::size_t>>();
    s.by_type = counts_from_json(j.at("constraints").at("by_type"));
    s.by_path = counts_from_json(j.at("constraints").at("by_path"));
    return s;
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(std::string("report.json: ") + e.what());
  }
}

namespace {

std::size_t soundings_of(const SubmapSet& set) {
  std::size_t n = 0;
  for (const Submap& s : set.submaps) n += s.points.size();
  return n;
}

// Each heading step: the submaps it lies between, DR's heading jump there, and how
// many registrations it explains that the white noise did not.
nlohmann::json heading_steps_json(const NavigationNoiseEstimate& e) {
  nlohmann::json steps = nlohmann::json::array();
  for (const auto& h : e.heading_steps) {
    steps.push_back({{"after_submap", h.step}, {"jump_deg", h.jump_rad * 180 / M_PI}, {"registrations_explained", h.explained}});
  }
  return steps;
}

nlohmann::json navigation_noise_json(const NavigationNoiseEstimate& e) {
  return {{"estimated", e.estimated},
          {"innovations", e.innovations},
          {"translation_scale", e.translation_scale},
          {"yaw_scale", e.yaw_scale},
          {"likeliest_translation_scale", e.likeliest_translation_scale},
          {"likeliest_yaw_scale", e.likeliest_yaw_scale},
          {"dr_sigma_translation_m", {e.graph.dr_sigma_translation_m.x(), e.graph.dr_sigma_translation_m.y(),
                                      e.graph.dr_sigma_translation_m.z()}},
          {"dr_sigma_rotation_rad", {e.graph.dr_sigma_rotation_rad.x(), e.graph.dr_sigma_rotation_rad.y(),
                                     e.graph.dr_sigma_rotation_rad.z()}},
          {"heading_steps", heading_steps_json(e)}};
}

}  // namespace

// Several surveys in one graph: each survey's submaps, its trajectory error (when every submap
// has a reference) and the registrations between it and the others.
struct SurveyPart {
  NodeRange submaps;
  std::optional<ErrorStats> trajectory, trajectory_dr;
  int cross_accepted = 0, cross_registered = 0;  // registrations with another survey's submap
};

std::vector<SurveyPart> survey_parts(const PipelineResult& r) {
  std::vector<SurveyPart> parts;
  const std::vector<int>& starts = r.submaps.survey_starts;
  if (starts.empty()) return parts;
  const int n = static_cast<int>(r.submaps.submaps.size());
  const bool every_reference = static_cast<int>(r.trajectory_errors.size()) == n;
  for (std::size_t k = 0; k <= starts.size(); ++k) {
    SurveyPart part;
    part.submaps = survey_nodes(starts, static_cast<int>(k), n);
    if (every_reference) {
      const auto slice = [&](const std::vector<double>& e) {
        return error_stats(std::vector<double>(e.begin() + part.submaps.begin, e.begin() + part.submaps.end));
      };
      part.trajectory = slice(r.trajectory_errors);
      part.trajectory_dr = slice(r.dr_trajectory_errors);
    }
    parts.push_back(part);
  }
  for (const Constraint& c : r.constraints) {
    if (from_navigation(c.type) || r.config.graph.same_survey(c.from, c.to)) continue;
    for (int survey : {survey_of(starts, c.from), survey_of(starts, c.to)}) {
      ++parts[survey].cross_registered;
      parts[survey].cross_accepted += c.in_graph() ? 1 : 0;
    }
  }
  return parts;
}

nlohmann::json site_json(const PipelineResult& r) {
  if (!r.site_consistency) return nullptr;
  nlohmann::json surveys = nlohmann::json::array();
  for (const SurveyPart& part : survey_parts(r)) {
    nlohmann::json j = {{"first_submap", part.submaps.begin}, {"submaps", part.submaps.size()},
                        {"registrations_with_other_surveys", {{"accepted", part.cross_accepted}, {"tried", part.cross_registered}}}};
    if (part.trajectory) {
      j["trajectory_error_m"] = {{"optimized", stats_json(*part.trajectory)}, {"dead_reckoning", stats_json(*part.trajectory_dr)}};
    }
    surveys.push_back(j);
  }
  const SiteConsistency &c = *r.site_consistency, &c0 = *r.dr_site_consistency;
  return {{"surveys", surveys},
          {"registrations_over_change", r.registrations_over_change},
          {"across_where_unchanged", r.across_where_unchanged},
          {"consistency_error_m",
           {{"within_surveys", {{"optimized", stats_json(c.within.stats)}, {"dead_reckoning", stats_json(c0.within.stats)}}},
            {"across_surveys", {{"optimized", stats_json(c.across.stats)}, {"dead_reckoning", stats_json(c0.across.stats)}}}}}};
}

nlohmann::json report_json(const PipelineResult& r) {
  const ReportSummary s = report_summary(r);
  nlohmann::json histogram = {{"bin_width_m", s.histogram.bin_width},
                              {"counts", s.histogram.counts},
                              {"dr_counts", r.dr_consistency.histogram.counts}};
  nlohmann::json timings = nlohmann::json::object();
  for (const StageTiming& t : r.timings) timings[t.stage] = t.seconds;
  nlohmann::json trajectory = {{"optimized", stats_json(s.trajectory)},
                               {"dead_reckoning", stats_json(s.trajectory_dr)},
                               {"aligned", {{"optimized", stats_json(error_stats(r.aligned_trajectory_errors))},
                                            {"dead_reckoning", stats_json(error_stats(r.dr_aligned_trajectory_errors))}}},
                               {"per_pose", r.trajectory_errors}};
  if (const auto why = trajectory_not_computed(r)) trajectory["not_computed"] = *why;
  nlohmann::json consistency = {{"optimized", stats_json(s.consistency)},
                                {"dead_reckoning", stats_json(s.consistency_dr)},
                                {"histogram", histogram}};
  if (const auto why = consistency_not_computed(r)) consistency["not_computed"] = *why;
  return {{"configuration", s.configuration},
          {"safety_net", safety_net_json(r.safety_net)},
          {"footprint", {{"spacing_m", r.submaps.footprint.spacing_m}, {"altitude_m", r.submaps.footprint.altitude_m},
                         {"scale", r.footprint_scale}}},
          {"parameters", parameters(r.config)},
          {"submaps", {{"count", r.submaps.submaps.size()},
                       {"soundings", soundings_of(r.submaps)},
                       {"lines", r.submaps.lines.size()},
                       {"pings_dropped_outside_navigation", r.submaps.pings_dropped}}},
          {"constraints", {{"by_type", counts_json(s.by_type)}, {"by_path", counts_json(s.by_path)},
                           {"switch_decisions", switch_decisions(r)}}},
          {"registrations", registrations_json(r)},
          {"navigation_noise", navigation_noise_json(r.navigation_noise)},
          {"graph", {{"converged", r.graph.converged}, {"iterations", r.graph.iterations},
                     {"initial_cost", r.graph.initial_cost}, {"final_cost", r.graph.final_cost},
                     {"batch_solves", r.batch_solves}, {"batch_solve_s", r.batch_solve_seconds}}},
          {"trajectory_error_m", trajectory},
          {"consistency_error_m", consistency},
          {"site", site_json(r)},
          {"timings_s", timings}};
}

std::string report_text(const PipelineResult& r) {
  const ErrorStats t = error_stats(r.trajectory_errors), t0 = error_stats(r.dr_trajectory_errors);
  const ErrorStats ta = error_stats(r.aligned_trajectory_errors), ta0 = error_stats(r.dr_aligned_trajectory_errors);
  const ErrorStats& c = r.consistency.stats;
  const ErrorStats& c0 = r.dr_consistency.stats;
  std::size_t registrations = 0, accepted = 0;
  for (const Constraint& k : r.constraints) {
    if (from_navigation(k.type)) continue;
    ++registrations;
    accepted += k.in_graph() ? 1 : 0;
  }
  std::string summary = format("configuration %s: %zu submaps on %zu lines, %zu/%zu registrations accepted\n",
                               to_string(r.config.configuration).c_str(), r.submaps.submaps.size(),
                               r.submaps.lines.size(), accepted, registrations);
  summary += format("footprint          soundings %.3g m apart, %.3g m below the sonar: Table 1's lengths x %g\n",
                    r.submaps.footprint.spacing_m, r.submaps.footprint.altitude_m, r.footprint_scale);
  if (const auto why = trajectory_not_computed(r)) {
    summary += "trajectory error   not computed: " + *why + "\n";
  } else {
    summary += format("trajectory error   rmse %.2f m, mean %.2f m, std %.2f m, max %.2f m (dead reckoning: rmse %.2f m)\n"
                      "  aligned (2D)     rmse %.2f m, max %.2f m (dead reckoning: rmse %.2f m)\n",
                      t.rmse, t.mean, t.std, t.max, t0.rmse, ta.rmse, ta.max, ta0.rmse);
  }
  for (const SurveyPart& part : survey_parts(r)) {
    summary += format("  survey at submap %d: %d submaps, %d/%d registrations with other surveys accepted",
                      part.submaps.begin, part.submaps.size(), part.cross_accepted, part.cross_registered);
    if (part.trajectory) {
      summary += format(", trajectory rmse %.2f m (dead reckoning %.2f m)", part.trajectory->rmse, part.trajectory_dr->rmse);
    }
    if (part.cross_accepted == 0) summary += ": no registration with another survey accepted, it stays where its navigation and start fix put it";
    summary += "\n";
  }
  if (r.registrations_over_change > 0) {
    summary += format("  %d registrations across surveys overlap a change of the seabed: their depth, roll and pitch left "
                      "out, the graph solved again\n", r.registrations_over_change);
  }
  if (const auto why = consistency_not_computed(r)) {
    summary += "consistency error  not computed: " + *why + "\n";
  } else {
    summary += format("consistency error  rmse %.3f m, p95 %.3f m, p99 %.3f m over %zu cells (dead reckoning: rmse %.3f m)\n",
                      c.rmse, c.p95, c.p99, c.count, c0.rmse);
  }
  if (r.site_consistency) {
    const SiteConsistency &site = *r.site_consistency, &site0 = *r.dr_site_consistency;
    const auto line = [](const char* label, const ErrorStats& now, const ErrorStats& before, const char* none) {
      if (now.count == 0 && before.count == 0) return format("  %-16s none: %s\n", label, none);
      return format("  %-16s consistency rmse %.3f m, p99 %.3f m over %zu cells (dead reckoning: rmse %.3f m)\n", label,
                    now.rmse, now.p99, now.count, before.rmse);
    };
    summary += line("within surveys", site.within.stats, site0.within.stats, "no cell seen by two submaps of one survey");
    summary += line("across surveys", site.across.stats, site0.across.stats, "no cell seen by two surveys");
    if (r.across_where_unchanged) summary += "                   (across: cells where the seabed changed left out)\n";
  }
  if (r.navigation_noise.estimated) {
    const NavigationNoiseEstimate& e = r.navigation_noise;
    summary += format("navigation noise   estimated from %.0f registrations: %.3f m and %.5f rad per submap step "
                      "(Table 1 x %.3f, x %.3f; likeliest x %.3f, x %.3f)\n",
                      static_cast<double>(e.innovations), e.graph.dr_sigma_translation_m.x(), e.graph.dr_sigma_rotation_rad.z(),
                      e.translation_scale, e.yaw_scale, e.likeliest_translation_scale, e.likeliest_yaw_scale);
    for (const auto& h : e.heading_steps) {
      summary += format("  heading step     %+.1f deg between submaps %d and %d (%d registrations explained by it)\n",
                        h.jump_rad * 180 / M_PI, h.step, h.step + 1, h.explained);
    }
  }
  if (r.safety_net.ran) summary += "safety net         " + r.safety_net.verdict + "\n";
  for (const std::string& d : r.safety_net.dropped) summary += "  dropped " + d + "\n";
  return summary;
}

namespace {

std::string not_computed_suffix(const std::optional<std::string>& why) { return why ? ": not computed, " + *why : ""; }

}  // namespace

void write_report_plots(const PipelineResult& r, const std::filesystem::path& dir) {
  auto histogram_series = [](const Histogram& h, const std::string& label, uint8_t red, uint8_t green, uint8_t blue) {
    Series s{label, {}, red, green, blue, true};
    for (std::size_t i = 0; i < h.counts.size(); ++i) s.points.emplace_back(i * h.bin_width, static_cast<double>(h.counts[i]));
    return s;
  };
  write_file_bytes(dir / "consistency_histogram.png",
             plot_png({"Consistency error (" + to_string(r.config.configuration) + ")" +
                           not_computed_suffix(consistency_not_computed(r)),
                       "consistency error (m)", "cells"},
                      {histogram_series(r.dr_consistency.histogram, "dead reckoning", 230, 120, 120),
                       histogram_series(r.consistency.histogram, "optimized", 40, 90, 200)}));

  auto per_pose = [](const std::vector<double>& errors, const std::string& label, uint8_t red, uint8_t green, uint8_t blue) {
    Series s{label, {}, red, green, blue, false};
    for (std::size_t i = 0; i < errors.size(); ++i) s.points.emplace_back(static_cast<double>(i), errors[i]);
    return s;
  };
  write_file_bytes(dir / "trajectory_error.png",
             plot_png({"Horizontal error against the reference" + not_computed_suffix(trajectory_not_computed(r)),
                       "submap (pose index)", "error (m)"},
                      {per_pose(r.dr_trajectory_errors, "dead reckoning", 220, 60, 60),
                       per_pose(r.trajectory_errors, "optimized", 40, 90, 200)}));

  Series reference{"reference", {}, 40, 160, 40}, dr{"dead reckoning", {}, 220, 60, 60},
      optimized{"optimized", {}, 40, 90, 200};
  for (std::size_t i = 0; i < r.submaps.submaps.size(); ++i) {
    const Submap& s = r.submaps.submaps[i];
    if (s.reference_pose) reference.points.emplace_back(s.reference_pose->translation().head<2>());
    dr.points.emplace_back(r.dr_poses[i].translation().head<2>());
    optimized.points.emplace_back(r.optimized_poses[i].translation().head<2>());
  }
  write_file_bytes(dir / "trajectory.png",
             plot_png({"Trajectory (submap poses)", "east of local origin (m)", "north of local origin (m)", true},
                      {reference, dr, optimized}));
}

}  // namespace bathyslam
