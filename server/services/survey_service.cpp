#include "server/services/survey_service.h"

#include "core/fuse/fuse.h"
#include "core/fuse/map_extent.h"
#include "core/fuse/map_resolution.h"
#include "core/io/bounded_json.h"
#include "core/io/crs.h"
#include "core/pipeline/streamed_survey.h"
#include "core/summary/survey_summary.h"
#include "server/log.h"
#include "server/services/chunk_writer.h"
#include "server/storage/stored_bundle.h"

namespace bathyslam::server {
namespace {

namespace storage = bathyslam::storage;

constexpr std::size_t kMaxChunkBytes = 1 << 20;
// At most this many bytes of an upload are committed in one transaction (ChunkWriter).
constexpr std::size_t kBatchBytes = 8 << 20;
// How long a resumed upload waits for an earlier stream of its file to store what it received.
constexpr std::chrono::seconds kEarlierStreamPatience{10};
// gRPC carries a status message in a trailer of limited size: the first problems go there,
// GetSurvey lists them all.
constexpr std::size_t kProblemsInStatus = 40;

// The free-form "sonar" and "vehicle" objects: as survey.json allows them (they come from it).
nlohmann::json object_field(const std::string& field, const std::string& text) {
  if (text.empty()) return nlohmann::json::object();
  nlohmann::json value;
  try {
    value = parse_bounded_json(text, kSurveyJsonLimits);
  } catch (const JsonLimitError& error) {
    throw invalid(field, error.what());
  } catch (const nlohmann::json::parse_error&) {
    throw invalid(field, "must be a JSON object");
  }
  if (!value.is_object()) throw invalid(field, "must be a JSON object");
  return value;
}

void describe_upload(const storage::UploadState& upload, v1::UploadStatus* reply) {
  reply->set_file_name(upload.name);
  reply->set_size_bytes(upload.size_bytes);
  reply->set_committed_bytes(upload.committed_bytes);
  reply->set_complete(upload.complete);
  reply->set_sha256(upload.sha256.data(), upload.sha256.size());
}

Refusal upload_refusal(const storage::UploadError& error) {
  using Kind = storage::UploadError::Kind;
  switch (error.kind()) {
    case Kind::kNotFound: return Refusal(grpc::StatusCode::NOT_FOUND, error.what());
    case Kind::kFinalized:
    case Kind::kConflict: return Refusal(grpc::StatusCode::FAILED_PRECONDITION, error.what());
    case Kind::kBadOffset: return Refusal(grpc::StatusCode::ABORTED, error.what());
    case Kind::kTooMany:
    case Kind::kQuota: return Refusal(grpc::StatusCode::RESOURCE_EXHAUSTED, error.what());
    case Kind::kChecksum:
    case Kind::kInvalid: break;
  }
  return Refusal(grpc::StatusCode::INVALID_ARGUMENT, error.what());
}

v1::Problem to_proto(const nlohmann::json& problem) {
  v1::Problem out;
  out.set_severity(problem.value("severity", "error") == "warning" ? v1::Problem::WARNING : v1::Problem::ERROR);
  out.set_file(problem.value("file", ""));
  out.set_line(problem.value("line", std::uint64_t{0}));
  out.set_field(problem.value("field", ""));
  out.set_message(problem.value("message", ""));
  return out;
}

nlohmann::json to_json(const Problem& problem) {
  return {{"severity", problem.severity == Problem::Severity::kWarning ? "warning" : "error"},
          {"file", problem.file},
          {"line", problem.line},
          {"field", printable(problem.field)},
          {"message", printable(problem.message)}};
}

// The first message declares the file and carries its first chunk: checked whole before the
// upload is declared, so that a refused stream leaves nothing behind.
void check_declaration(const v1::UploadFileRequest& message, const Limits& limits) {
  const std::string& name = message.file_name();
  check_text("file_name", name);
  if (!storage::is_bundle_file(name))
    throw invalid("file_name", quoted_input(name) + " is not a survey file (survey.json, nav.csv, pings.csv, reference_nav.csv, NAME.gsf, NAME.all or NAME.xtf)");
  if (message.sha256().size() != 32) throw invalid("sha256", "must be the 32 bytes of the file's SHA-256");
  if (message.size_bytes() < 0) throw invalid("size_bytes", "must not be negative");
  if (message.offset() < 0) throw invalid("offset", "must not be negative");
  if (message.data().size() > kMaxChunkBytes) throw invalid("data", "a chunk holds at most 1 MiB");
  if (message.offset() + static_cast<std::int64_t>(message.data().size()) > message.size_bytes())
    throw invalid("data", quoted_input(name) + " was declared " + std::to_string(message.size_bytes()) +
                              " bytes; this chunk would end at " +
                              std::to_string(message.offset() + static_cast<std::int64_t>(message.data().size())));
  if (message.size_bytes() > limits.max_file_bytes)
    throw Refusal(grpc::StatusCode::RESOURCE_EXHAUSTED, "size_bytes: " + std::to_string(message.size_bytes()) +
                                                            " is over this server's limit of " +
                                                            std::to_string(limits.max_file_bytes));
  if (name == kSurveyJsonFile && message.size_bytes() > static_cast<std::int64_t>(kSurveyJsonLimits.max_bytes))
    throw invalid("size_bytes", "survey.json is at most " + std::to_string(kSurveyJsonLimits.max_bytes) + " bytes, not " +
                                    std::to_string(message.size_bytes()));
}

// Where the declared upload resumes: the committed bytes of the same declaration, or 0 for a new
// (or changed) one. A first chunk anywhere else is refused before the declaration is stored.
void check_first_offset(storage::SurveyStore& surveys, std::int64_t survey_id, const v1::UploadFileRequest& message,
                        const storage::Sha256& digest) {
  const auto existing = surveys.upload_state(survey_id, message.file_name());
  const bool resumed = existing && existing->size_bytes == message.size_bytes() && existing->sha256 == digest;
  const std::int64_t committed = resumed ? existing->committed_bytes : 0;
  if (message.offset() != committed)
    throw Refusal(grpc::StatusCode::ABORTED, "offset: " + std::to_string(message.offset()) + " but " + std::to_string(committed) +
                                                 " bytes of " + quoted_input(message.file_name()) + " are committed; resume there");
}

// Later messages carry chunks of the same file: one that names another file or survey, changes
// the declaration or carries nothing is a client error, not something to guess about.
void check_continuation(const v1::UploadFileRequest& first, const v1::UploadFileRequest& message) {
  if (message.survey_id() != 0 && message.survey_id() != first.survey_id())
    throw invalid("survey_id", "a stream uploads to one survey; a later message names survey " + std::to_string(message.survey_id()));
  if (!message.file_name().empty() && message.file_name() != first.file_name())
    throw invalid("file_name", "a stream uploads one file; a later message names " + quoted_input(message.file_name()));
  if ((message.size_bytes() != 0 && message.size_bytes() != first.size_bytes()) ||
      (!message.sha256().empty() && message.sha256() != first.sha256()))
    throw invalid("size_bytes", "the declaration (size_bytes, sha256) is made once, in the first message");
  if (message.data().empty()) throw invalid("data", "an empty chunk: only the first message may carry no data");
  if (message.data().size() > kMaxChunkBytes) throw invalid("data", "a chunk holds at most 1 MiB");
}

}  // namespace

void SurveyService::describe(const storage::SurveyRecord& survey, bool details, v1::Survey* reply) {
  reply->set_id(survey.id);
  reply->set_name(survey.name);
  reply->set_crs(survey.crs);
  reply->set_sonar_json(survey.sonar.dump());
  reply->set_vehicle_json(survey.vehicle.dump());
  reply->set_state(survey.ready ? v1::Survey::READY : v1::Survey::UPLOADING);
  if (!details) return;
  for (const storage::UploadState& upload : context_.surveys.uploads(survey.id)) describe_upload(upload, reply->add_files());
  if (auto validation = context_.surveys.validation(survey.id)) {
    for (const nlohmann::json& problem : validation->problems) *reply->add_problems() = to_proto(problem);
    if (!validation->summary.is_null()) reply->set_summary_json(validation->summary.dump());
  }
}

grpc::Status SurveyService::CreateSurvey(grpc::ServerContext* call, const v1::CreateSurveyRequest* request,
                                         v1::Survey* reply) {
  return handle("CreateSurvey", call, [&] {
    const std::int64_t tenant = caller_tenant(context_, *call);
    if (request->name().empty()) throw invalid("name", "a survey needs a name");
    check_name("name", request->name());
    if (!request->crs().empty())
      if (auto problem = crs_problem(request->crs())) throw invalid("crs", *problem);
    const nlohmann::json sonar = object_field("sonar_json", request->sonar_json());
    const nlohmann::json vehicle = object_field("vehicle_json", request->vehicle_json());
    const auto same_name = context_.surveys.list_surveys(tenant, 0, 1, request->name());
    if (!same_name.empty())
      throw Refusal(grpc::StatusCode::ALREADY_EXISTS, "name: survey " + std::to_string(same_name.front().id) + " is named " +
                                                          quoted_input(request->name()) + " already");
    std::int64_t id = 0;
    try {  // another call may take the name between the look above and the insert
      id = context_.surveys.create_survey(tenant, request->name(), request->crs(), sonar, vehicle);
    } catch (const storage::SurveyNameTaken& taken) {
      throw Refusal(grpc::StatusCode::ALREADY_EXISTS, taken.what());
    }
    log("survey %lld created: %s", static_cast<long long>(id), quoted_input(request->name()).c_str());
    describe(*context_.surveys.survey(id), true, reply);
  });
}

grpc::Status SurveyService::UploadFile(grpc::ServerContext* call, grpc::ServerReader<v1::UploadFileRequest>* reader,
                                       v1::UploadStatus* reply) {
  return handle("UploadFile", call, [&] {
    const std::int64_t tenant = caller_tenant(context_, *call);
    v1::UploadFileRequest first;
    if (!reader->Read(&first)) throw invalid("survey_id", "the stream ended before its first message");
    const std::int64_t survey_id = first.survey_id();
    const std::string& name = first.file_name();
    owned_survey(context_, tenant, survey_id);
    check_declaration(first, context_.limits);
    const StreamSlots::Slot slot = slot_or_refuse(upload_slots_, tenant, "UploadFile streams in progress",
                                                  "--max-upload-streams", "let one finish first");
    const FilesBeingWritten::Mark writing = files_being_written_.mark_when_idle({survey_id, name}, kEarlierStreamPatience);
    storage::Sha256 digest{};
    std::copy(first.sha256().begin(), first.sha256().end(), digest.begin());
    check_first_offset(context_.surveys, survey_id, first, digest);
    try {
      storage::UploadState state = context_.surveys.begin_upload(survey_id, name, first.size_bytes(), digest);
      // A stream from the file's start hashes as it goes, so the whole file is not read back.
      std::optional<storage::Sha256Stream> from_start;
      if (first.offset() == 0) from_start.emplace();
      ChunkWriter writer(
          [&](const std::vector<ChunkWriter::Chunk>& chunks) {
            return context_.surveys.append_chunks(survey_id, name, chunks, from_start ? &*from_start : nullptr);
          },
          kBatchBytes);
      auto append = [&](const v1::UploadFileRequest& message) {
        writer.add({message.offset(), storage::Bytes(message.data().begin(), message.data().end())});
      };
      // A bad message ends the call; the writer still stores what arrived before it (its
      // destructor), as when each chunk was committed alone.
      if (!first.data().empty()) append(first);
      v1::UploadFileRequest message;
      while (reader->Read(&message)) {
        check_continuation(first, message);
        append(message);
      }
      state = writer.finish(state);
      describe_upload(state, reply);
      if (state.complete) log("survey %lld: %s uploaded, %lld bytes", static_cast<long long>(survey_id), quoted_input(name).c_str(),
                              static_cast<long long>(state.size_bytes));
    } catch (const storage::UploadError& error) {
      throw upload_refusal(error);
    }
  });
}

grpc::Status SurveyService::GetUploadStatus(grpc::ServerContext* call, const v1::GetUploadStatusRequest* request,
                                            v1::UploadStatus* reply) {
  return handle("GetUploadStatus", call, [&] {
    owned_survey(context_, caller_tenant(context_, *call), request->survey_id());
    check_text("file_name", request->file_name());
    files_being_written_.wait_until_idle({request->survey_id(), request->file_name()}, kEarlierStreamPatience);
    auto state = context_.surveys.upload_state(request->survey_id(), request->file_name());
    if (!state) throw Refusal(grpc::StatusCode::NOT_FOUND, "file_name: no upload of " + quoted_input(request->file_name()));
    describe_upload(*state, reply);
  });
}

grpc::Status SurveyService::FinalizeSurvey(grpc::ServerContext* call, const v1::FinalizeSurveyRequest* request,
                                           v1::Survey* reply) {
  return handle("FinalizeSurvey", call, [&] {
    const std::int64_t tenant = caller_tenant(context_, *call);
    const storage::SurveyRecord survey = owned_survey(context_, tenant, request->survey_id());
    if (survey.ready) return describe(survey, true, reply);  // finalizing twice changes nothing
    const StreamSlots::Slot slot = slot_or_refuse(finalize_slots_, tenant, "FinalizeSurvey calls in progress",
                                                  "--max-finalizes", "try again when one ends");
    nlohmann::json problems = nlohmann::json::array();
    bool errors = false;
    const std::vector<storage::UploadState> uploads = context_.surveys.uploads(survey.id);  // what is validated
    for (const storage::UploadState& upload : uploads) {
      if (upload.complete) continue;
      problems.push_back(to_json({Problem::Severity::kError, upload.name, 0, "",
                                  "upload incomplete: " + std::to_string(upload.committed_bytes) + " of " +
                                      std::to_string(upload.size_bytes) + " bytes"}));
      errors = true;
    }
    // Read as a job reads it, the pings streamed: only their outlines are kept, never the soundings.
    PingOutlines outlines;
    BundleReadResult bundle = storage::StoredSurvey(context_.surveys, survey.id, scratch_).read(outlines);
    for (const Problem& problem : bundle.problems) {
      problems.push_back(to_json(problem));
      errors = errors || problem.severity == Problem::Severity::kError;
    }
    if (bundle.survey && !survey.crs.empty() && bundle.survey->metadata.crs != survey.crs) {
      problems.push_back(to_json({Problem::Severity::kError, std::string(kSurveyJsonFile), 0, "crs",
                                  quoted_input(bundle.survey->metadata.crs) + " but the survey was created with " + quoted_input(survey.crs)}));
      errors = true;
    }
    if (bundle.survey) {
      const double resolution = auto_map_resolution(outlines.swept_area(bundle.survey->nav), FuseConfig{}.min_soundings);
      if (auto problem = map_extent_problem(map_extent(bundle.survey->nav, outlines.sounding_reach_m(), resolution),
                                            resolution, context_.limits.max_map_cells)) {
        problems.push_back(to_json(*problem));
        errors = true;
      }
    }
    storage::Validation validation{!errors, problems, nullptr};
    if (!errors && bundle.survey) {
      bundle.survey->pings = outlines.pings_without_beams();
      validation.summary = to_json(summarize(*bundle.survey, outlines.footprint(bundle.survey->nav)));
    }
    if (!context_.surveys.save_validation_if_unchanged(survey.id, validation, uploads))
      throw Refusal(grpc::StatusCode::ABORTED, "survey " + std::to_string(survey.id) +
                                                   ": its files changed while it was validated; finalize it again");
    log("survey %lld finalized: %s, %zu problems", static_cast<long long>(survey.id), errors ? "invalid" : "ready",
        problems.size());
    if (errors) {
      std::string text = "survey " + std::to_string(survey.id) + " is not valid:";
      std::size_t listed = 0;
      for (const nlohmann::json& problem : problems) {
        if (listed++ == kProblemsInStatus) {
          text += "\n  ... and " + std::to_string(problems.size() - kProblemsInStatus) + " more (GetSurvey lists all)";
          break;
        }
        v1::Problem p = to_proto(problem);
        text += "\n  " + Problem{p.severity() == v1::Problem::WARNING ? Problem::Severity::kWarning : Problem::Severity::kError,
                                 p.file(), p.line(), p.field(), p.message()}
                             .to_string();
      }
      throw Refusal(grpc::StatusCode::INVALID_ARGUMENT, text);
    }
    describe(*context_.surveys.survey(survey.id), true, reply);
  });
}

grpc::Status SurveyService::GetSurvey(grpc::ServerContext* call, const v1::GetSurveyRequest* request, v1::Survey* reply) {
  return handle("GetSurvey", call, [&] {
    describe(owned_survey(context_, caller_tenant(context_, *call), request->survey_id()), true, reply);
  });
}

grpc::Status SurveyService::ListSurveys(grpc::ServerContext* call, const v1::ListSurveysRequest* request,
                                        v1::ListSurveysResponse* reply) {
  return handle("ListSurveys", call, [&] {
    const std::int64_t tenant = caller_tenant(context_, *call);
    const int size = page_size(request->page_size());
    const std::optional<std::string> name = name_filter("name", request->name());
    // One more than asked: whether there is a next page.
    auto surveys = context_.surveys.list_surveys(tenant, page_token(request->page_token()), size + 1, name);
    const bool more = trim_to_page(surveys, size);
    for (const storage::SurveyRecord& survey : surveys) describe(survey, false, reply->add_surveys());
    if (more) reply->set_next_page_token(std::to_string(surveys.back().id));
    const storage::StorageUse use = context_.surveys.storage_use(tenant);
    reply->set_stored_bytes(use.stored_bytes);
    reply->set_quota_bytes(use.quota_bytes.value_or(-1));
  });
}

grpc::Status SurveyService::DeleteSurvey(grpc::ServerContext* call, const v1::DeleteSurveyRequest* request,
                                         v1::DeleteSurveyResponse*) {
  return handle("DeleteSurvey", call, [&] {
    owned_survey(context_, caller_tenant(context_, *call), request->survey_id());
    context_.surveys.delete_survey(request->survey_id());
    log("survey %lld deleted", static_cast<long long>(request->survey_id()));
  });
}

}  // namespace bathyslam::server
