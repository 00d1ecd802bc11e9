#pragma once
// How a config struct lists its tunable fields, so that `--set`, a job's stored parameters and
// the report all name a field by its path in the config ("registration.gicp.neighbours") and
// none can be forgotten (core/pipeline/parameters.h; parameters_test walks every byte).
//
// Each config struct has a member
//   template <typename Field> void fields(Field&& field) { field("name", member, min, max); ... }
// where `field` takes the name, a reference to the member (an arithmetic type, bool or enum)
// and the range a value must lie in. A nested config hands its own fields on under its name.
#include <string>
#include <string_view>
#include <utility>

#include <Eigen/Core>

namespace bathyslam {

// `field`, with every name put under `prefix` ("gicp" + "neighbours" -> "gicp.neighbours").
template <typename Field>
auto under(std::string_view prefix, Field& field) {
  return [prefix = std::string(prefix) + ".", &field](std::string_view name, auto& member, double min, double max) {
    field(prefix + std::string(name), member, min, max);
  };
}

// A nested config's fields under its name.
template <typename Config, typename Field>
void nested(std::string_view name, Config& config, Field& field) {
  config.fields(under(name, field));
}

// A translation vector as name.x, name.y, name.z.
template <typename Field>
void xyz(std::string_view name, Eigen::Vector3d& v, double min, double max, Field& field) {
  auto f = under(name, field);
  f("x", v.x(), min, max);
  f("y", v.y(), min, max);
  f("z", v.z(), min, max);
}

// A rotation vector (roll, pitch, yaw) as name.roll, name.pitch, name.yaw.
template <typename Field>
void rpy(std::string_view name, Eigen::Vector3d& v, double min, double max, Field& field) {
  auto f = under(name, field);
  f("roll", v.x(), min, max);
  f("pitch", v.y(), min, max);
  f("yaw", v.z(), min, max);
}

}  // namespace bathyslam
