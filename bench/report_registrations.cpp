#include "bench/report_registrations.h"

#include <fstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace bathyslam::bench {
namespace {

ReportRegistration registration_of(const nlohmann::json& j, int submaps) {
  ReportRegistration r;
  r.from = j.at("from").get<int>();
  r.to = j.at("to").get<int>();
  if (r.from < 0 || r.from >= submaps || r.to < 0 || r.to >= submaps) {
    throw std::runtime_error("from/to outside the bundle's " + std::to_string(submaps) +
                             " submaps (a report of another bundle?)");
  }
  r.type = j.at("type").get<std::string>();
  r.path = j.value("path", "");
  r.accepted = j.at("accepted").get<bool>();
  r.has_measured = j.contains("measured");
  if (r.has_measured) {
    const auto t = j.at("measured").at("translation_m").get<std::vector<double>>();
    const auto q = j.at("measured").at("rotation_wxyz").get<std::vector<double>>();
    const auto a = j.at("anchor_m").get<std::vector<double>>();
    if (t.size() != 3 || q.size() != 4 || a.size() != 3) throw std::runtime_error("measured or anchor_m has the wrong size");
    r.measured.linear() = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
    r.measured.translation() = Eigen::Vector3d(t[0], t[1], t[2]);
    r.anchor = Eigen::Vector3d(a[0], a[1], a[2]);
  }
  if (r.accepted && j.contains("information_diagonal")) {
    const auto d = j.at("information_diagonal").get<std::vector<double>>();
    if (d.size() != 6) throw std::runtime_error("information_diagonal does not hold 6 values");
    r.information = Eigen::Matrix<double, 6, 1>(d.data()).asDiagonal();
  }
  return r;
}

}  // namespace

Report read_report(const std::string& path, int submaps) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot be read");
  Report report;
  nlohmann::json registrations;
  try {
    const nlohmann::json parsed = nlohmann::json::parse(in);
    report.config = preset_config(parse_configuration(parsed.at("configuration").get<std::string>()));
    for (const auto& [key, value] : parsed.at("parameters").items()) {
      set_parameter(report.config, key, value.get<double>());
    }
    registrations = parsed.at("registrations");
  } catch (const std::exception& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
  for (std::size_t k = 0; k < registrations.size(); ++k) {
    try {
      report.registrations.push_back(registration_of(registrations[k], submaps));
    } catch (const std::exception& e) {
      throw std::runtime_error(path + ": registrations[" + std::to_string(k) + "]: " + e.what());
    }
  }
  return report;
}

}  // namespace bathyslam::bench
