#include "core/products/corrected_gsf.h"

#include "core/io/gsf/gsf_survey.h"
#include "core/pipeline/corrected_navigation.h"

namespace bathyslam {

std::uint64_t write_corrected_gsf(const Survey& survey, const PipelineResult& result, const std::filesystem::path& path,
                                  const std::function<BundleReadResult(PingSink&)>& read_pings) {
  gsf::SurveyWriter writer(path, corrected_navigation(survey, result));
  BundleReadResult read = read_pings(writer);
  if (!read.survey) throw BundleError(std::move(read.problems));
  return writer.close();
}

}  // namespace bathyslam
