#pragma once
// The real GSF files the tests read (shared data folder, see tests/CMakeLists.txt).
#include <filesystem>
#include <vector>

#include "core/io/gsf/gsf_reader.h"

namespace bathyslam::gsf::test {

inline const std::filesystem::path kData = BATHYSLAM_GSF_DATA;
inline const std::filesystem::path kEx1811 = kData / "EX1811_EM302_0059_20181102_212138.gsf";
inline const std::filesystem::path kGsfpy = kData / "gsfpy_test_data.gsf";

// Every record of `source`.
inline std::vector<Record> records_of(ByteSource& source, const std::string& name) {
  Reader reader(source, name);
  std::vector<Record> records;
  while (auto r = reader.next()) records.push_back(std::move(*r));
  return records;
}

inline std::vector<Ping> pings_of(const std::vector<Record>& records) {
  std::vector<Ping> pings;
  for (const Record& r : records) {
    if (const auto* p = std::get_if<Ping>(&r)) pings.push_back(*p);
  }
  return pings;
}

}  // namespace bathyslam::gsf::test
