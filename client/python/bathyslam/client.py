"""Client: the bathyslam API as a few calls, with the CLI's semantics (client/upload_command.cpp,
client/job_commands.cpp): an upload finds the survey an interrupted one left and sends each file
from what the server has committed; UNAVAILABLE answers are waited out during an upload."""
import hashlib
import json
import os
import time

import grpc

from bathyslam.errors import JobFailed, NotFound, Unavailable, error_of
from bathyslam.v1 import (job_pb2, job_pb2_grpc, map_pb2, map_pb2_grpc, site_pb2, site_pb2_grpc, survey_pb2,
                          survey_pb2_grpc)

CHUNK = 1 << 20  # the API's largest chunk
BUNDLE_FILES = ("survey.json", "nav.csv", "pings.csv", "reference_nav.csv")
SONAR_EXTENSIONS = (".gsf", ".all", ".xtf")
FORMATS = {"cog": map_pb2.COG, "bag": map_pb2.BAG, "gsf": map_pb2.GSF, "difference": map_pb2.DIFFERENCE}
FINISHED = {job_pb2.SUCCEEDED: "succeeded", job_pb2.FAILED: "failed", job_pb2.CANCELLED: "cancelled"}


def _job(job):
    """A Job message as a dict, its state as the HTTP API and the CLI name it."""
    return {"id": job.id, "survey_id": job.survey_id, "configuration": job.configuration,
            "state": job_pb2.JobState.Name(job.state).lower(), "stage": job.stage, "progress": job.progress,
            "attempts": job.attempts, "error": job.error, "created_at": job.created_at, "started_at": job.started_at,
            "finished_at": job.finished_at, "parameters": dict(job.parameters),
            "more_survey_ids": list(job.more_survey_ids), "site_id": job.site_id}


def _site(site):
    """A Site message as a dict: its surveys in order, the first the datum."""
    return {"id": site.id, "name": site.name, "survey_ids": list(site.survey_ids), "created_at": site.created_at}


def _sha256(path):
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(4 << 20), b""):
            digest.update(block)
    return digest.digest()


class Client:
    """A connection to bathyslam-server. `token`: an API token (`bathyslam-server token create`);
    None on a development server. `root_certificates`: PEM bytes of the CA of a TLS server."""

    def __init__(self, server="127.0.0.1:50051", token=None, *, root_certificates=None, timeout=60,
                 retry_seconds=300):
        options = [("grpc.max_receive_message_length", 64 << 20)]
        self._channel = (grpc.secure_channel(server, grpc.ssl_channel_credentials(root_certificates), options)
                         if root_certificates else grpc.insecure_channel(server, options))
        self._metadata = [("authorization", "Bearer " + token)] if token else []
        self._timeout, self._retry_seconds = timeout, retry_seconds
        self._surveys = survey_pb2_grpc.SurveyServiceStub(self._channel)
        self._jobs = job_pb2_grpc.JobServiceStub(self._channel)
        self._maps = map_pb2_grpc.MapServiceStub(self._channel)
        self._sites = site_pb2_grpc.SiteServiceStub(self._channel)

    def close(self):
        self._channel.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def _call(self, name, method, request, timeout=None):
        try:
            return method(request, timeout=timeout or self._timeout, metadata=self._metadata)
        except grpc.RpcError as error:
            raise error_of(name, error) from None

    def _retrying(self, step):
        """`step()`, again after a growing pause while the server answers UNAVAILABLE."""
        give_up, pause = time.monotonic() + self._retry_seconds, 1.0
        while True:
            try:
                return step()
            except Unavailable:
                if time.monotonic() + pause > give_up:
                    raise
                time.sleep(pause)
                pause = min(2 * pause, 15.0)

    # Surveys

    def upload(self, *paths, name=None, crs="", reference_nav=None, progress=None):
        """Uploads a survey bundle folder, or sonar files (.gsf, .all or .xtf, one format), and
        finalizes it; returns its id. Run again after an interruption (even a killed process), it
        resumes: the survey of the same name is found and each file continues from what the
        server has committed. `progress(file_name, sent_bytes, size_bytes)` after each chunk."""
        files, declared = self._local_files(paths, name, crs, reference_nav)
        found = self._retrying(lambda: self._call("ListSurveys", self._surveys.ListSurveys,
                                                  survey_pb2.ListSurveysRequest(name=declared["name"])))
        if found.surveys:
            survey = found.surveys[0]
            if survey.state == survey_pb2.Survey.READY:
                return survey.id
            survey_id = survey.id
        else:
            request = survey_pb2.CreateSurveyRequest(name=declared["name"], crs=declared["crs"],
                                                     sonar_json=json.dumps(declared["sonar"]),
                                                     vehicle_json=json.dumps(declared["vehicle"]))
            survey_id = self._retrying(lambda: self._call("CreateSurvey", self._surveys.CreateSurvey, request)).id
        for file_name, path in files:
            self._retrying(lambda: self._upload_file(survey_id, file_name, path, progress))
        self._retrying(lambda: self._call("FinalizeSurvey", self._surveys.FinalizeSurvey,
                                          survey_pb2.FinalizeSurveyRequest(survey_id=survey_id), timeout=600))
        return survey_id

    @staticmethod
    def _local_files(paths, name, crs, reference_nav):
        """[(name on the server, local path)] and the survey's declaration, as the CLI makes them."""
        if len(paths) == 1 and os.path.isdir(paths[0]):
            folder = paths[0]
            with open(os.path.join(folder, "survey.json"), encoding="utf-8") as f:
                meta = json.load(f)
            declared = {"name": name or meta.get("name") or os.path.basename(os.path.normpath(folder)),
                        "crs": meta.get("crs", ""), "sonar": meta.get("sonar", {}), "vehicle": meta.get("vehicle", {})}
            return [(f, os.path.join(folder, f)) for f in BUNDLE_FILES if os.path.isfile(os.path.join(folder, f))], declared
        extension = os.path.splitext(paths[0])[1].lower() if paths else ""
        if extension not in SONAR_EXTENSIONS or any(os.path.splitext(p)[1].lower() != extension for p in paths):
            raise ValueError("upload: one bundle folder, or sonar files of one format (.gsf, .all or .xtf)")
        files = [(os.path.basename(p), p) for p in paths]
        if reference_nav:
            files.append(("reference_nav.csv", reference_nav))
        return files, {"name": name or os.path.splitext(os.path.basename(paths[0]))[0], "crs": crs, "sonar": {},
                       "vehicle": {}}

    def _upload_file(self, survey_id, file_name, path, progress):
        size, digest = os.path.getsize(path), _sha256(path)
        offset = 0
        try:
            status = self._call("GetUploadStatus", self._surveys.GetUploadStatus,
                                survey_pb2.GetUploadStatusRequest(survey_id=survey_id, file_name=file_name))
            if status.size_bytes == size and status.sha256 == digest:
                if status.complete:
                    return
                offset = status.committed_bytes
        except NotFound:  # not begun yet
            pass

        def requests():
            with open(path, "rb") as f:
                f.seek(offset)
                sent, first = offset, True
                while first or sent < size:
                    data = f.read(CHUNK)
                    if not data and sent < size:  # the file shrank while it was being sent
                        raise ValueError(f"{path}: shorter than the {size} bytes it had")
                    message = survey_pb2.UploadFileRequest(offset=sent, data=data)
                    if first:
                        message.survey_id, message.file_name = survey_id, file_name
                        message.size_bytes, message.sha256 = size, digest
                    yield message
                    sent += len(data)
                    first = False
                    if progress:
                        progress(file_name, sent, size)

        reply = self._call("UploadFile " + file_name, self._surveys.UploadFile, requests(), timeout=24 * 3600)
        if not reply.complete:
            raise Unavailable("UploadFile " + file_name, grpc.StatusCode.UNAVAILABLE,
                              f"stopped at {reply.committed_bytes} of {size} bytes")

    # Jobs

    def submit(self, survey_id=0, config="mchs", parameters=None, more_survey_ids=(), *, site_id=0,
               reference_survey_id=0):
        """Queues a SLAM job (odometry, gicp or mchs; `parameters` overrides by name); its id.
        `more_survey_ids`: other surveys of the site, joined with `survey_id` (the datum) in one graph;
        or `site_id`: every survey of a site, in its order. `reference_survey_id`: the datum, when
        not the first."""
        request = job_pb2.SubmitJobRequest(survey_id=survey_id, configuration=config,
                                           parameters={k: str(v) for k, v in (parameters or {}).items()},
                                           more_survey_ids=list(more_survey_ids), site_id=site_id,
                                           reference_survey_id=reference_survey_id)
        return self._call("SubmitJob", self._jobs.SubmitJob, request).id

    def create_site(self, name):
        """A new, empty site of this name; its id."""
        return self._call("CreateSite", self._sites.CreateSite, site_pb2.CreateSiteRequest(name=name)).id

    def add_surveys(self, site_id, survey_ids):
        """Appends the surveys to the site in order (all or none); the site as a dict."""
        return _site(self._call("AddSurveys", self._sites.AddSurveys,
                                site_pb2.AddSurveysRequest(site_id=site_id, survey_ids=list(survey_ids))))

    def site(self, site_id):
        return _site(self._call("GetSite", self._sites.GetSite, site_pb2.GetSiteRequest(site_id=site_id)))

    def job(self, job_id):
        return _job(self._call("GetJob", self._jobs.GetJob, job_pb2.GetJobRequest(job_id=job_id)))

    def watch(self, job_id, progress=None, timeout=24 * 3600):
        """Waits for the job to end, calling `progress(stage, fraction, message)` for each event;
        returns the job (a dict) when it succeeded, raises JobFailed when it failed or was cancelled."""
        deadline = time.monotonic() + timeout
        while True:  # a stream the server ended early (a restart) is opened again
            try:
                for event in self._jobs.WatchJob(job_pb2.WatchJobRequest(job_id=job_id), metadata=self._metadata,
                                                 timeout=max(1.0, deadline - time.monotonic())):
                    if progress:
                        progress(event.stage, event.progress, event.message)
                    if event.state in FINISHED:
                        break
            except grpc.RpcError as error:
                raise error_of("WatchJob", error) from None
            job = self.job(job_id)
            if job["state"] not in ("queued", "running") or time.monotonic() >= deadline:
                break
        if job["state"] != "succeeded":
            raise JobFailed(job)
        return job

    def report(self, job_id):
        """The job's quality report as `bathyslam report --out` saves report.json (a dict)."""
        reply = self._call("GetReport", self._jobs.GetReport, job_pb2.GetReportRequest(job_id=job_id))
        return json.loads(reply.report_json)

    def download_map(self, job_id, path, format="cog", epoch=None, from_epoch=1):
        """Writes the job's map to `path`: "cog" (GeoTIFF), "bag", "gsf" (the pings with the
        corrected navigation; in a job of several surveys survey `epoch`'s, 1 to N, the first by
        default) or "difference" (a job of several surveys: the change from survey `from_epoch`, the
        first by default, to survey `epoch`, 2 by default); written to a temporary name first, so `path` is whole or absent."""
        survey = (epoch or 0) if format == "gsf" else 0
        epoch = (epoch or 2) if format == "difference" else 0
        if format not in FORMATS:
            raise ValueError(f"download_map: format must be one of {sorted(FORMATS)}, not {format!r}")
        partial = path + ".part"
        try:
            with open(partial, "wb") as out:
                for chunk in self._maps.GetMap(map_pb2.GetMapRequest(job_id=job_id, format=FORMATS[format], epoch=epoch,
                                                                     from_epoch=from_epoch, survey=survey),
                                               timeout=3600, metadata=self._metadata):
                    out.write(chunk.data)
        except BaseException as error:  # a refusal, a full disk, Ctrl-C: no half file stays
            if os.path.exists(partial):
                os.remove(partial)
            if isinstance(error, grpc.RpcError):
                raise error_of("GetMap", error) from None
            raise
        os.replace(partial, path)
        return path
