#pragma once
// What every sonar-format reader (GSF, Kongsberg .all, XTF) takes and gives: the options of a
// reading and the survey with one summary per file.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/types/survey.h"

namespace bathyslam {

struct SonarReadOptions {
  std::string crs;  // "EPSG:<code>"; empty: the WGS 84 UTM zone of the first position
  std::optional<std::filesystem::path> reference_nav;  // a nav.csv-format file
  // false: every ping keeps its sounding count but no sounding is kept (Survey::beams stays
  // empty), so that a summary needs the memory of the navigation, not of the soundings.
  bool keep_soundings = true;
};

template <class FileSummary>
struct SonarRead {
  Survey survey;
  std::vector<FileSummary> files;
};

}  // namespace bathyslam
