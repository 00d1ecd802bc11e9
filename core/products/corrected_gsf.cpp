#include "core/products/corrected_gsf.h"

#include "core/io/gsf/gsf_survey.h"
#include "core/pipeline/corrected_navigation.h"

namespace bathyslam {

std::uint64_t write_corrected_gsf(const Survey& survey, const PipelineResult& result, const std::filesystem::path& path) {
  return gsf::write_survey(survey, corrected_navigation(survey, result), path);
}

}  // namespace bathyslam
