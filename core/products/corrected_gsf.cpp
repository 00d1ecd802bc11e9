#include "core/products/corrected_gsf.h"

#include "core/io/gsf/gsf_survey.h"
#include "core/pipeline/corrected_navigation.h"

namespace bathyslam {

std::string corrected_gsf_name(int survey_number) {
  return survey_number <= 1 ? kCorrectedGsfFile : "corrected." + std::to_string(survey_number) + ".gsf";
}

std::uint64_t write_corrected_gsf(const Survey& survey, const PipelineResult& result, const std::filesystem::path& path,
                                  const std::function<BundleReadResult(PingSink&)>& read_pings, int survey_index) {
  gsf::SurveyWriter writer(path, corrected_navigation(survey, result, survey_index));
  BundleReadResult read = read_pings(writer);
  if (!read.survey) throw BundleError(std::move(read.problems));
  return writer.close();
}

}  // namespace bathyslam
