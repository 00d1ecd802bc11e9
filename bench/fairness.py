#!/usr/bin/env python3
"""Fair sharing under hostile load (issue 37, docs/service.md): tenant A opens STREAMS WatchJob
streams on its own queued job, tenant B runs FINALIZERS concurrent FinalizeSurvey calls on a survey
that finalize refuses (its declared CRS is not survey.json's, so every call reads and checks the
whole survey again), and meanwhile tenant C calls ListSurveys for SECONDS. Prints C's latency
percentiles and failures, how A's streams and B's finalizes were answered, and the server's threads
and resident memory sampled each second. Run by bench/fairness.sh, which starts the server.
Usage: /usr/bin/python3 bench/fairness.py ADDRESS SERVER_PID BUNDLE TOKEN_A TOKEN_B TOKEN_C JOB_A
       [--streams 2000] [--finalizers 24] [--seconds 30]"""
import argparse
import collections
import hashlib
import os
import threading
import time

import grpc

from bathyslam.v1 import job_pb2, job_pb2_grpc, survey_pb2, survey_pb2_grpc

CHUNK = 1 << 20


def process_status(pid):
    """(threads, resident MB) of the server process."""
    fields = {}
    with open(f"/proc/{pid}/status") as status:
        for line in status:
            key, _, value = line.partition(":")
            fields[key] = value.split()
    return int(fields["Threads"][0]), int(fields["VmRSS"][0]) / 1024


def metadata(token):
    return [("authorization", "Bearer " + token)]


def upload(stub, token, survey_id, path):
    data = open(path, "rb").read()
    def requests():
        for offset in range(0, max(len(data), 1), CHUNK):
            request = survey_pb2.UploadFileRequest(offset=offset, data=data[offset:offset + CHUNK])
            if offset == 0:
                request.survey_id, request.file_name = survey_id, os.path.basename(path)
                request.size_bytes, request.sha256 = len(data), hashlib.sha256(data).digest()
            yield request
    stub.UploadFile(requests(), metadata=metadata(token), timeout=300)


def refused_survey(address, token, bundle):
    """A survey whose every FinalizeSurvey reads it whole and then refuses it."""
    stub = survey_pb2_grpc.SurveyServiceStub(grpc.insecure_channel(address))
    survey_id = stub.CreateSurvey(survey_pb2.CreateSurveyRequest(name="refused at finalize", crs="EPSG:32633"),
                                  metadata=metadata(token), timeout=30).id
    for name in ("survey.json", "nav.csv", "pings.csv"):
        upload(stub, token, survey_id, os.path.join(bundle, name))
    return survey_id


def finalizer(address, token, survey_id, until, codes, lock):
    stub = survey_pb2_grpc.SurveyServiceStub(grpc.insecure_channel(address))
    while time.monotonic() < until:
        try:
            stub.FinalizeSurvey(survey_pb2.FinalizeSurveyRequest(survey_id=survey_id), metadata=metadata(token), timeout=120)
            code = grpc.StatusCode.OK
        except grpc.RpcError as error:
            code = error.code()
        with lock:
            codes[code.name] += 1
        if code == grpc.StatusCode.RESOURCE_EXHAUSTED:
            time.sleep(0.05)  # a refused caller tries again soon, not in a tight loop


def lister(address, token, until, latencies, errors):
    stub = survey_pb2_grpc.SurveyServiceStub(grpc.insecure_channel(address))
    while time.monotonic() < until:
        started = time.monotonic()
        try:
            stub.ListSurveys(survey_pb2.ListSurveysRequest(), metadata=metadata(token), timeout=30)
            latencies.append(time.monotonic() - started)
        except grpc.RpcError as error:
            errors.append(f"{error.code().name}: {error.details()}")
        time.sleep(0.01)


def percentile(ordered, q):
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))] * 1000


def main():
    parser = argparse.ArgumentParser()
    for name in ("address", "pid", "bundle", "token_a", "token_b", "token_c", "job"):
        parser.add_argument(name)
    parser.add_argument("--streams", type=int, default=2000)
    parser.add_argument("--finalizers", type=int, default=24)
    parser.add_argument("--seconds", type=float, default=30)
    o = parser.parse_args()
    pid = int(o.pid)
    threads0, rss0 = process_status(pid)
    survey_b = refused_survey(o.address, o.token_b, o.bundle)

    # A's streams over channels of 50 each (one HTTP/2 connection carries only so many at once).
    channels = [grpc.insecure_channel(o.address) for _ in range((o.streams + 49) // 50)]
    calls = []
    for k in range(o.streams):
        stub = job_pb2_grpc.JobServiceStub(channels[k // 50])
        calls.append(stub.WatchJob(job_pb2.WatchJobRequest(job_id=int(o.job)), metadata=metadata(o.token_a),
                                   timeout=o.seconds + 120))
    until = time.monotonic() + o.seconds
    codes, lock = collections.Counter(), threading.Lock()
    latencies, errors = [], []
    workers = [threading.Thread(target=finalizer, args=(o.address, o.token_b, survey_b, until, codes, lock))
               for _ in range(o.finalizers)]
    workers.append(threading.Thread(target=lister, args=(o.address, o.token_c, until, latencies, errors)))
    for worker in workers:
        worker.start()
    samples = []
    while time.monotonic() < until:
        samples.append(process_status(pid))
        time.sleep(1)
    for worker in workers:
        worker.join()
    streams = collections.Counter("open" if not call.done() else call.code().name for call in calls)
    for call in calls:
        call.cancel()
    time.sleep(3)
    threads_after, rss_after = process_status(pid)

    latencies.sort()
    print(f"tenant A: {o.streams} WatchJob streams asked: " + ", ".join(f"{n} {what}" for what, n in sorted(streams.items())))
    print(f"tenant B: {o.finalizers} FinalizeSurvey callers for {o.seconds:.0f} s: "
          + ", ".join(f"{n} {what}" for what, n in sorted(codes.items())))
    if latencies:
        print(f"tenant C: {len(latencies)} ListSurveys, p50 {percentile(latencies, 0.5):.1f} ms, "
              f"p99 {percentile(latencies, 0.99):.1f} ms, max {latencies[-1] * 1000:.1f} ms, {len(errors)} failed")
    else:
        print(f"tenant C: no ListSurveys answered, {len(errors)} failed")
    for error in errors[:5]:
        print("  " + error)
    print(f"server: threads {threads0} before, {min(t for t, _ in samples)}-{max(t for t, _ in samples)} during, "
          f"{threads_after} after; RSS {rss0:.0f} MB before, max {max(r for _, r in samples):.0f} MB during, "
          f"{rss_after:.0f} MB after")


if __name__ == "__main__":
    main()
