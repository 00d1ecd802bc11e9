#include "core/products/corrected_gsf.h"

#include "core/io/bundle.h"
#include "core/io/gsf/gsf_survey.h"
#include "core/pipeline/corrected_navigation.h"

namespace bathyslam {

std::uint64_t write_corrected_gsf(const Survey& survey, const PipelineResult& result, const std::filesystem::path& path) {
  return gsf::write_survey(survey, corrected_navigation(survey, result), path);
}

std::uint64_t write_corrected_gsf(const std::filesystem::path& bundle, const Survey& survey, const PipelineResult& result,
                                  const std::filesystem::path& path) {
  gsf::SurveyWriter writer(path, corrected_navigation(survey, result));
  BundleReadResult read = stream_bundle(bundle, writer);
  if (!read.survey) throw BundleError(std::move(read.problems));
  return writer.close();
}

}  // namespace bathyslam
