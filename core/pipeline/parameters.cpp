#include "core/pipeline/parameters.h"

#include <charconv>
#include <cmath>
#include <optional>
#include <type_traits>

namespace bathyslam {
namespace {

// Names before 2026-12, when they did not yet follow the fields' paths: stored jobs and scripts
// may still use them. A prefix rename ends with '.'.
constexpr std::pair<std::string_view, std::string_view> kRenamed[] = {
    {"gicp.sigma_x_m", "uniform_information.sigma_translation_m.x"},
    {"gicp.sigma_y_m", "uniform_information.sigma_translation_m.y"},
    {"gicp.sigma_z_m", "uniform_information.sigma_translation_m.z"},
    {"gicp.sigma_roll_rad", "uniform_information.sigma_rotation_rad.roll"},
    {"gicp.sigma_pitch_rad", "uniform_information.sigma_rotation_rad.pitch"},
    {"gicp.sigma_yaw_rad", "uniform_information.sigma_rotation_rad.yaw"},
    {"graph.dr_sigma_x_m", "graph.dr_sigma_translation_m.x"},
    {"graph.dr_sigma_y_m", "graph.dr_sigma_translation_m.y"},
    {"graph.dr_sigma_z_m", "graph.dr_sigma_translation_m.z"},
    {"graph.dr_sigma_roll_rad", "graph.dr_sigma_rotation_rad.roll"},
    {"graph.dr_sigma_pitch_rad", "graph.dr_sigma_rotation_rad.pitch"},
    {"graph.dr_sigma_yaw_rad", "graph.dr_sigma_rotation_rad.yaw"},
    {"quality.sigma_x_m", "quality.best_sigma_translation_m.x"},
    {"quality.sigma_y_m", "quality.best_sigma_translation_m.y"},
    {"quality.sigma_z_m", "quality.best_sigma_translation_m.z"},
    {"quality.sigma_roll_rad", "quality.best_sigma_rotation_rad.roll"},
    {"quality.sigma_pitch_rad", "quality.best_sigma_rotation_rad.pitch"},
    {"quality.sigma_yaw_rad", "quality.best_sigma_rotation_rad.yaw"},
    {"robust.plausibility_chi2", "robustness.pcm.plausibility.chi2_threshold"},
    {"robust.pair_chi2", "robustness.pcm.pair_chi2_threshold"},
    {"robust.safety_net_p", "robustness.line_check.p"},
    {"batch_submaps", "stages.batch_submaps"},
    {"gicp.", "registration.gicp."},
    {"register.", "registration."},
    {"matching.", "registration.matching."},
    {"ransac.", "registration.ransac."},
    {"switch.", "registration.switching."},
    {"uniqueness.", "registration.uniqueness."},
    {"accept.", "acceptance."},
    {"robust.", "robustness."},
    {"eval.", "consistency."},
};

std::string current_name(const std::string& name) {
  for (const auto& [old_name, new_name] : kRenamed) {
    if (old_name.back() != '.' && name == old_name) return std::string(new_name);
    if (old_name.back() == '.' && name.rfind(old_name, 0) == 0) return std::string(new_name) + name.substr(old_name.size());
  }
  return name;
}

// Sets `name` to `value` (nullopt: the text was not a number) after the range check; messages
// quote the value as the caller gave it (`shown`).
void assign_parameter(PipelineConfig& config, const std::string& given_name, std::optional<double> value,
                      const std::string& shown) {
  const std::string name = current_name(given_name);
  bool found = false;
  config.fields([&](std::string_view key, auto& field, double min, double max) {
    if (key != name) return;
    found = true;
    using Field = std::remove_reference_t<decltype(field)>;
    constexpr bool integer = std::is_integral_v<Field> || std::is_enum_v<Field>;
    if (!value || !std::isfinite(*value)) {
      throw std::invalid_argument("parameter '" + given_name + "': '" + shown + "' is not a number");
    }
    const double v = *value;
    if (v < min || v > max || (integer && v != std::floor(v))) {
      throw std::invalid_argument("parameter '" + given_name + "': " + shown + " is outside [" +
                                  std::to_string(min) + ", " + std::to_string(max) + "]" +
                                  (integer ? " or not an integer" : ""));
    }
    // The one field whose valid values are not a range (tsd_keypoints.h).
    if (name == "keypoints.descriptor_size") {
      if (const auto fault = descriptor_size_fault(static_cast<int>(v))) {
        throw std::invalid_argument("parameter '" + given_name + "': " + shown + " " + *fault);
      }
    }
    if constexpr (std::is_enum_v<Field>) {
      field = static_cast<Field>(static_cast<std::underlying_type_t<Field>>(v));
    } else {
      field = static_cast<Field>(v);
    }
  });
  if (!found) throw std::invalid_argument("unknown parameter '" + given_name + "'");
}

}  // namespace

void set_parameter(PipelineConfig& config, const std::string& name, const std::string& value) {
  std::optional<double> number;
  try {
    std::size_t used = 0;
    const double v = std::stod(value, &used);
    if (used == value.size()) number = v;
  } catch (const std::exception&) {
  }
  assign_parameter(config, name, number, value);
}

void set_parameter(PipelineConfig& config, const std::string& name, double value) {
  char text[32];
  const auto end = std::to_chars(text, text + sizeof text, value).ptr;
  assign_parameter(config, name, value, std::string(text, end));
}

void set_parameter(PipelineConfig& config, std::string_view assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string_view::npos) {
    throw std::invalid_argument("expected name=value, got '" + std::string(assignment) + "'");
  }
  set_parameter(config, std::string(assignment.substr(0, eq)), std::string(assignment.substr(eq + 1)));
}

namespace {

template <typename Value>
PipelineConfig configured(const std::string& preset, const std::map<std::string, Value>& overrides) {
  PipelineConfig config;
  try {
    config = preset_config(preset.empty() ? Configuration::kMchs : parse_configuration(preset));
  } catch (const std::invalid_argument& error) {
    throw ConfigurationError("configuration", error.what());
  }
  for (const auto& [name, value] : overrides) {
    try {
      set_parameter(config, name, value);
    } catch (const std::invalid_argument& error) {
      throw ConfigurationError("parameters[" + name + "]", error.what());
    }
  }
  return config;
}

}  // namespace

PipelineConfig configuration_of(const std::string& preset, const std::map<std::string, std::string>& overrides) {
  return configured(preset, overrides);
}

PipelineConfig configuration_of(const std::string& preset, const std::map<std::string, double>& overrides) {
  return configured(preset, overrides);
}

std::map<std::string, std::string> overrides_of(const std::vector<std::string>& assignments) {
  std::map<std::string, std::string> overrides;
  for (const std::string& assignment : assignments) {
    const auto eq = assignment.find('=');
    if (eq == std::string::npos) {
      throw ConfigurationError("parameters", "expected name=value, got '" + assignment + "'");
    }
    overrides[assignment.substr(0, eq)] = assignment.substr(eq + 1);
  }
  return overrides;
}

std::map<std::string, double> parameters(const PipelineConfig& config) {
  std::map<std::string, double> out;
  PipelineConfig copy = config;  // `fields` hands out references that may be written; these are not
  copy.fields([&](std::string_view key, auto& field, double, double) {
    using Field = std::remove_reference_t<decltype(field)>;
    if constexpr (std::is_enum_v<Field>) {
      out[std::string(key)] = static_cast<double>(static_cast<std::underlying_type_t<Field>>(field));
    } else {
      out[std::string(key)] = static_cast<double>(field);
    }
  });
  return out;
}

namespace {

// The power of `scale` a parameter's value goes with: 1 for a length, 2 for an area, 0 for the rest.
int length_power(std::string_view name) {
  if (name.starts_with("footprint.")) return 0;
  if (name.ends_with("_m2")) return 2;
  if (name.ends_with("_m") || name.starts_with("quality.best_sigma_translation_m.")) return 1;
  return 0;
}

}  // namespace

double footprint_scale(const SoundingFootprint& footprint, const PipelineConfig& config) {
  return config.footprint.scale > 0 ? config.footprint.scale : length_scale(footprint);
}

PipelineConfig scaled_to_footprint(const PipelineConfig& config, double scale) {
  if (scale == 1) return config;
  const std::map<std::string, double> preset = parameters(preset_config(config.configuration));
  PipelineConfig scaled = config;
  scaled.fields([&](std::string_view key, auto& field, double, double) {
    const int power = length_power(key);
    using Field = std::remove_reference_t<decltype(field)>;
    if constexpr (std::is_floating_point_v<Field>) {
      if (power > 0 && static_cast<double>(field) == preset.at(std::string(key))) {
        field = static_cast<Field>(field * std::pow(scale, power));
      }
    }
  });
  return scaled;
}

}  // namespace bathyslam
