#pragma once
// A configuration's fields by name: `--set`, a job's stored parameters and the report's. Names
// are the fields' paths in PipelineConfig ("registration.gicp.neighbours"), listed beside each
// struct (its `fields`); every field is settable and range-checked.
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/pipeline/pipeline_config.h"
#include "core/submaps/sounding_footprint.h"

namespace bathyslam {

// Sets one parameter by its name; throws std::invalid_argument naming the parameter when the
// name is unknown or the value out of range. Names from before the fields were named by their
// paths ("gicp.neighbours") are still read, so that stored jobs and old scripts keep working.
void set_parameter(PipelineConfig& config, const std::string& name, const std::string& value);
// The same for a number already parsed (a job's stored parameters, a report's).
void set_parameter(PipelineConfig& config, const std::string& name, double value);
// The same from one "name=value" argument (`--set`); a missing '=' is named too.
void set_parameter(PipelineConfig& config, std::string_view assignment);
// Every parameter by name with its current value.
std::map<std::string, double> parameters(const PipelineConfig& config);

// A configuration that cannot be made, with the field at fault as a request names it:
// "configuration" or "parameters[NAME]".
class ConfigurationError : public std::invalid_argument {
 public:
  ConfigurationError(std::string field, const std::string& message)
      : std::invalid_argument(message), field_(std::move(field)) {}
  const std::string& field() const { return field_; }

 private:
  std::string field_;
};

// The one way a preset and overrides become a configuration (`process --set`, a submitted job's
// parameters, a stored job's): `preset`'s fields (empty: mchs, the full method), then each
// override by name, in name order, so that the first bad one reported is the same every time.
// Throws ConfigurationError.
PipelineConfig configuration_of(const std::string& preset, const std::map<std::string, std::string>& overrides);
PipelineConfig configuration_of(const std::string& preset, const std::map<std::string, double>& overrides);
// `--set` arguments ("name=value", the last of a name winning) as overrides; throws
// ConfigurationError for one without '='.
std::map<std::string, std::string> overrides_of(const std::vector<std::string>& assignments);

// How many times Table 1's lengths a survey of this footprint needs: `config.footprint.scale`
// when set, else length_scale (sounding_footprint.h).
double footprint_scale(const SoundingFootprint& footprint, const PipelineConfig& config);
// `config` with every length (a parameter named *_m, the best sigmas of quality) still at its
// preset's value times `scale`, every area (*_m2) times its square. A length set to any other
// value is the user's and stays as given.
PipelineConfig scaled_to_footprint(const PipelineConfig& config, double scale);

}  // namespace bathyslam
