#!/usr/bin/env python3
"""Hostile input, as a table: malformed upload streams, requests, JSON, job parameters and
bundle files, each answered with its status code and a message that names the field (or the
file and line), the server still up, and the database unchanged: every table's row count and
checksum are compared before and after each case. A refused FinalizeSurvey records its
diagnosis (survey_validations, which GetSurvey lists) and changes nothing else; that table is
left out of the comparison for those cases, and the survey checked still UPLOADING. The same
environment as service_api_test.py (set by ctest)."""
import hashlib
import os
import re
import unittest
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Callable

import grpc

from service_api_test import Server, database_fingerprint, job_pb2, map_pb2, read, survey_pb2, token, upload_requests

INVALID, NOT_FOUND = grpc.StatusCode.INVALID_ARGUMENT, grpc.StatusCode.NOT_FOUND
ABORTED, PRECONDITION = grpc.StatusCode.ABORTED, grpc.StatusCode.FAILED_PRECONDITION
DEEP = '{"a": ' + "[" * 100000 + "]" * 100000 + "}"  # about 200 KB, under the message limit
FORGED_LINE = "2026-12-05T00:00:00.000Z survey 1 deleted"  # what a name with a newline could add to the log
HUGE_NAME = "x" * 1_900_000  # echoed whole, it made a status trailer over gRPC's metadata limit
# What a refusal quotes of a long input: its first 64 bytes and its size.
HUGE_QUOTED = "'" + "x" * 64 + "…' \\(1900000 bytes\\)"
# What no message to a client may hold: PostgreSQL's words or SQL state, a server path.
INTERNALS = re.compile(r"database error|SQLSTATE|ERROR: |/tmp/|/var/|scratch|\.s\.PGSQL")


def tiny_bundle(**replace):
    """A valid survey of 20 s (the control case finalizes it READY); `replace` swaps one file's
    bytes (None: the file is left out)."""
    nav = "time,easting,northing,depth,roll,pitch,heading\n" + "".join(
        f"{1720000000 + t},{452000 + 2 * t},4630000,1,0,0,90\n" for t in range(21))
    pings = "time,beam,along,across,down\n" + "".join(
        f"{1720000000 + t + 0.5},{b},0,{b - 5},20\n" for t in range(20) for b in range(11))
    files = {"survey.json": b'{"name": "tiny", "crs": "EPSG:32651"}', "nav.csv": nav.encode(), "pings.csv": pings.encode()}
    files.update(replace)
    return {name: data for name, data in files.items() if data is not None}


@dataclass
class Case:
    name: str
    act: Callable  # (test) -> None; raises grpc.RpcError
    code: grpc.StatusCode
    message: str   # regular expression the status message must match from its start
    finalize: bool = False  # the act is a FinalizeSurvey: its diagnosis is stored


class HostileInputTableTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.server = Server()
        cls.surveys, cls.jobs, cls.maps = cls.server.surveys, cls.server.jobs, cls.server.maps
        cls.intruder = [("authorization", "Bearer " + token(cls.server.url, "create", "--tenant", "intruder"))]
        cls.uploading = cls.create("uploading")
        # nav.csv half uploaded into `uploading`: the resumed stream cases continue it.
        cls.nav = read("nav.csv")
        cls.nav_sha = hashlib.sha256(cls.nav).digest()
        cls.half = 1 << 19
        status = cls.surveys.UploadFile(iter([cls.message(cls, offset=0, data=cls.nav[:cls.half])]), timeout=60)
        assert status.committed_bytes == cls.half, status
        cls.ready = cls.tiny_survey("ready", tiny_bundle())
        cls.surveys.FinalizeSurvey(survey_pb2.FinalizeSurveyRequest(survey_id=cls.ready), timeout=60)
        cls.finalized_case = 0

    @classmethod
    def tearDownClass(cls):
        cls.server.stop()

    @classmethod
    def create(cls, name, crs="EPSG:32651"):
        return cls.surveys.CreateSurvey(survey_pb2.CreateSurveyRequest(name=name, crs=crs), timeout=30).id

    @classmethod
    def tiny_survey(cls, name, files):
        survey_id = cls.create(name)
        for file_name, data in files.items():
            assert cls.surveys.UploadFile(upload_requests(survey_id, file_name, data), timeout=60).complete, file_name
        return survey_id

    def message(self, **fields):
        """An UploadFile message continuing the half-uploaded nav.csv of `uploading`, or declaring it."""
        values = dict(survey_id=self.uploading, file_name="nav.csv", size_bytes=len(self.nav), sha256=self.nav_sha,
                      offset=self.half)
        values.update(fields)
        return survey_pb2.UploadFileRequest(**values)

    def upload(self, *messages, metadata=()):
        self.surveys.UploadFile(iter(messages), metadata=metadata, timeout=60)

    def finalize_bundle(self, files):
        """FinalizeSurvey of a new survey holding `files` (uploaded before the case's act)."""
        self.__class__.finalized_case += 1
        survey_id = self.tiny_survey(f"bundle {self.finalized_case}", files)

        def act(_):
            try:
                self.surveys.FinalizeSurvey(survey_pb2.FinalizeSurveyRequest(survey_id=survey_id), timeout=60)
            finally:
                state = self.surveys.GetSurvey(survey_pb2.GetSurveyRequest(survey_id=survey_id), timeout=30).state
                self.assertEqual(state, survey_pb2.Survey.UPLOADING)
        return act

    def cases(self):
        m, up = self.message, self.upload
        continuation = dict(survey_id=0, file_name="", size_bytes=0, sha256=b"")  # as clients send chunks 2..n
        big_chunk = b"x" * ((1 << 20) + 1)
        create = self.surveys.CreateSurvey
        submit = self.jobs.SubmitJob

        def call(rpc, request, metadata=()):
            return lambda _: rpc(request, metadata=metadata, timeout=60)

        def job_with(**parameters):
            return call(submit, job_pb2.SubmitJobRequest(survey_id=self.ready, configuration="mchs", parameters=parameters))

        upload = [
            Case("negative size", lambda _: up(m(size_bytes=-1, offset=0)), INVALID, "size_bytes: must not be negative"),
            Case("size over the limit", lambda _: up(m(size_bytes=9 << 30, offset=0)), grpc.StatusCode.RESOURCE_EXHAUSTED,
                 "size_bytes: 9663676416 is over this server's limit"),
            Case("negative offset", lambda _: up(m(offset=-5, data=b"x")), INVALID, "offset: must not be negative"),
            Case("oversize first chunk", lambda _: up(m(offset=0, data=big_chunk)), INVALID, "data: a chunk holds at most 1 MiB"),
            Case("first chunk past the declared size", lambda _: up(m(size_bytes=10, offset=0, data=b"x" * 20)), INVALID,
                 "data: 'nav.csv' was declared 10 bytes; this chunk would end at 20"),
            Case("unknown file name", lambda _: up(m(file_name="extra.csv", offset=0)), INVALID,
                 "file_name: 'extra.csv' is not a survey file"),
            Case("path in the file name", lambda _: up(m(file_name="../nav.csv", offset=0)), INVALID,
                 "file_name: '../nav.csv' is not a survey file"),
            Case("no file name", lambda _: up(m(file_name="", offset=0)), INVALID, "file_name: '' is not a survey file"),
            Case("short sha256", lambda _: up(m(sha256=b"12345")), INVALID, "sha256: must be the 32 bytes"),
            Case("empty stream", lambda _: up(), INVALID, "survey_id: the stream ended before its first message"),
            Case("survey id 0", lambda _: up(m(survey_id=0)), INVALID, "survey_id: must be positive"),
            Case("unknown survey", lambda _: up(m(survey_id=987654)), NOT_FOUND, "survey_id: no survey 987654"),
            Case("another tenant's survey", lambda _: up(m(), metadata=self.intruder), NOT_FOUND, r"survey_id: no survey \d+"),
            Case("into a finalized survey", lambda _: up(m(survey_id=self.ready, file_name="reference_nav.csv", offset=0)),
                 PRECONDITION, r"survey \d+ is finalized"),
            Case("new file starting past 0", lambda _: up(m(file_name="pings.csv", offset=100, data=b"x")), ABORTED,
                 "offset: 100 but 0 bytes of 'pings.csv' are committed; resume there"),
            Case("resume at the wrong offset", lambda _: up(m(offset=0, data=b"t")), ABORTED,
                 f"offset: 0 but {self.half} bytes of 'nav.csv' are committed; resume there"),
            Case("later chunk at the wrong offset", lambda _: up(m(), m(**continuation, offset=self.half + 7, data=b"x")),
                 ABORTED, f"offset: {self.half + 7} but {self.half} bytes"),
            Case("later oversize chunk", lambda _: up(m(), m(**continuation, data=big_chunk)), INVALID,
                 "data: a chunk holds at most 1 MiB"),
            Case("later chunk past the declared size",
                 lambda _: up(m(), m(**continuation, data=self.nav[self.half:] + b"x")), INVALID,
                 f"data: 'nav.csv' was declared {len(self.nav)} bytes; this chunk would end at {len(self.nav) + 1}"),
            Case("later empty chunk", lambda _: up(m(), m(**continuation)), INVALID, "data: an empty chunk"),
            Case("later message names another file", lambda _: up(m(), m(**{**continuation, "file_name": "pings.csv"}, data=b"x")),
                 INVALID, "file_name: a stream uploads one file; a later message names 'pings.csv'"),
            Case("later message names another survey", lambda _: up(m(), m(**{**continuation, "survey_id": self.ready}, data=b"x")),
                 INVALID, f"survey_id: a stream uploads to one survey; a later message names survey {self.ready}"),
            Case("later message changes the size", lambda _: up(m(), m(**{**continuation, "size_bytes": 5}, data=b"x")), INVALID,
                 r"size_bytes: the declaration \(size_bytes, sha256\) is made once"),
            Case("file name with a NUL", lambda _: up(m(file_name="nav.csv\0", offset=0)), INVALID,
                 r"file_name: holds a NUL byte \(at byte 7\): 'nav.csv\\x00'"),
            Case("file name of 1.9 MB", lambda _: up(m(file_name=HUGE_NAME, offset=0)), INVALID,
                 "file_name: " + HUGE_QUOTED + " is not a survey file"),
            Case("survey.json over its limit", lambda _: up(m(file_name="survey.json", size_bytes=2 << 20, offset=0)), INVALID,
                 "size_bytes: survey.json is at most 1048576 bytes"),
        ]
        requests = [
            Case("survey without a name", call(create, survey_pb2.CreateSurveyRequest()), INVALID, "name: a survey needs a name"),
            Case("survey name taken", call(create, survey_pb2.CreateSurveyRequest(name="ready")), grpc.StatusCode.ALREADY_EXISTS,
                 r"name: survey \d+ is named 'ready' already"),
            Case("survey name of 2.7 kB", call(create, survey_pb2.CreateSurveyRequest(name="n" * 2700)), INVALID,
                 "name: at most 255 bytes, not 2700: 'n{64}…' \\(2700 bytes\\)"),
            Case("survey name with a NUL", call(create, survey_pb2.CreateSurveyRequest(name="coll\0one")), INVALID,
                 r"name: holds a NUL byte \(at byte 4\): 'coll\\x00one'"),
            Case("survey name with a newline",
                 call(create, survey_pb2.CreateSurveyRequest(name="a\n" + FORGED_LINE)), INVALID,
                 r"name: must be UTF-8 without control characters: 'a\\x0a2026"),
            Case("survey name with an escape", call(create, survey_pb2.CreateSurveyRequest(name="red \x1b[31m")), INVALID,
                 "name: must be UTF-8 without control characters"),
            Case("listing by a name with a NUL", call(self.surveys.ListSurveys, survey_pb2.ListSurveysRequest(name="ready\0")),
                 INVALID, "name: holds a NUL byte"),
            Case("sonar_json with \\u0000", call(create, survey_pb2.CreateSurveyRequest(name="a", sonar_json='{"a": "\\u0000"}')),
                 INVALID, "sonar_json: a string holds"),
            Case("vehicle_json with \\u0000 in a nested key",
                 call(create, survey_pb2.CreateSurveyRequest(name="a", vehicle_json='{"a": [{"b\\u0000": 1}]}')),
                 INVALID, "vehicle_json: a string holds"),
            Case("geographic CRS", call(create, survey_pb2.CreateSurveyRequest(name="a", crs="EPSG:4326")), INVALID, "crs: "),
            Case("unknown CRS", call(create, survey_pb2.CreateSurveyRequest(name="a", crs="EPSG:999999")), INVALID, "crs: "),
            Case("sonar_json not JSON", call(create, survey_pb2.CreateSurveyRequest(name="a", sonar_json="{oops")), INVALID,
                 "sonar_json: must be a JSON object"),
            Case("vehicle_json an array", call(create, survey_pb2.CreateSurveyRequest(name="a", vehicle_json="[1]")), INVALID,
                 "vehicle_json: must be a JSON object"),
            Case("sonar_json nested 100 000 deep", call(create, survey_pb2.CreateSurveyRequest(name="a", sonar_json=DEEP)),
                 INVALID, "sonar_json: nested deeper than 64 levels"),
            Case("vehicle_json nested 100 000 deep", call(create, survey_pb2.CreateSurveyRequest(name="a", vehicle_json=DEEP)),
                 INVALID, "vehicle_json: nested deeper than 64 levels"),
            Case("sonar_json of 1.5 MiB",
                 call(create, survey_pb2.CreateSurveyRequest(name="a", sonar_json='{"a": "' + "x" * (1536 << 10) + '"}')),
                 INVALID, "sonar_json: larger than 1048576 bytes"),
            Case("vehicle_json with a number beyond a double",
                 call(create, survey_pb2.CreateSurveyRequest(name="a", vehicle_json='{"a": 6e524}')), INVALID, "vehicle_json: "),
            Case("unknown configuration", call(submit, job_pb2.SubmitJobRequest(survey_id=self.ready, configuration="fast")),
                 INVALID, "configuration: "),
            Case("unknown parameter", job_with(**{"registration.nope": "1"}), INVALID, r"parameters\[registration.nope\]: "),
            Case("parameter out of range", job_with(**{"registration.gicp.neighbours": "-3"}), INVALID,
                 r"parameters\[registration.gicp.neighbours\]: "),
            Case("parameter not a number", job_with(**{"registration.gicp.neighbours": "many"}), INVALID,
                 r"parameters\[registration.gicp.neighbours\]: "),
            Case("parameter NaN", job_with(**{"registration.gicp.max_correspondence_m": "nan"}), INVALID,
                 r"parameters\[registration.gicp.max_correspondence_m\]: "),
            Case("parameter name of 1.9 MB", job_with(**{HUGE_NAME: "1"}), INVALID, "parameters: at most 128 bytes"),
            Case("configuration of 1.9 MB", call(submit, job_pb2.SubmitJobRequest(survey_id=self.ready, configuration=HUGE_NAME)),
                 INVALID, "configuration: at most 128 bytes, not 1900000: " + HUGE_QUOTED),
            Case("parameter empty", job_with(**{"registration.gicp.neighbours": ""}), INVALID,
                 r"parameters\[registration.gicp.neighbours\]: "),
            Case("job on a survey not ready", call(submit, job_pb2.SubmitJobRequest(survey_id=self.uploading, configuration="mchs")),
                 PRECONDITION, rf"survey_id: survey {self.uploading} is not ready"),
            Case("job on survey -1", call(submit, job_pb2.SubmitJobRequest(survey_id=-1, configuration="mchs")), INVALID,
                 "survey_id: must be positive"),
            Case("job on another tenant's survey",
                 call(submit, job_pb2.SubmitJobRequest(survey_id=self.ready, configuration="mchs"), self.intruder),
                 NOT_FOUND, rf"survey_id: no survey {self.ready}"),
            Case("page size -1", call(self.surveys.ListSurveys, survey_pb2.ListSurveysRequest(page_size=-1)), INVALID, "page_size: "),
            Case("page size 5000", call(self.jobs.ListJobs, job_pb2.ListJobsRequest(page_size=5000)), INVALID, "page_size: "),
            Case("forged page token", call(self.jobs.ListJobs, job_pb2.ListJobsRequest(page_token="abc")), INVALID,
                 "page_token: 'abc' is not a token this server gave"),
            Case("tile of job 0", lambda _: list(self.maps.GetTile(map_pb2.GetTileRequest(job_id=0), timeout=60)), INVALID,
                 "job_id: must be positive"),
            Case("status of a file never uploaded",
                 call(self.surveys.GetUploadStatus, survey_pb2.GetUploadStatusRequest(survey_id=self.uploading, file_name="pings.csv")),
                 NOT_FOUND, "file_name: no upload of 'pings.csv'"),
            Case("status of a file name with a NUL",
                 call(self.surveys.GetUploadStatus, survey_pb2.GetUploadStatusRequest(survey_id=self.uploading, file_name="nav.csv\0")),
                 INVALID, "file_name: holds a NUL byte"),
            Case("status of a file name of 1.9 MB",
                 call(self.surveys.GetUploadStatus, survey_pb2.GetUploadStatusRequest(survey_id=self.uploading, file_name=HUGE_NAME)),
                 NOT_FOUND, "file_name: no upload of " + HUGE_QUOTED),
            Case("forged page token of 1.9 MB", call(self.jobs.ListJobs, job_pb2.ListJobsRequest(page_token=HUGE_NAME)), INVALID,
                 "page_token: " + HUGE_QUOTED + " is not a token this server gave"),
            Case("CRS of 1.9 MB", call(create, survey_pb2.CreateSurveyRequest(name="a", crs=HUGE_NAME)), INVALID,
                 "crs: " + HUGE_QUOTED + " is not of the form EPSG:<code>"),
            Case("delete another tenant's survey",
                 call(self.surveys.DeleteSurvey, survey_pb2.DeleteSurveyRequest(survey_id=self.ready), self.intruder),
                 NOT_FOUND, rf"survey_id: no survey {self.ready}"),
        ]
        nav, pings = tiny_bundle()["nav.csv"], tiny_bundle()["pings.csv"]
        bundles = [
            ("nav.csv without its heading column", dict(**{"nav.csv": nav.replace(b",heading", b"", 1)}), r"[\s\S]*nav\.csv"),
            ("nav.csv with a word for a number", {"nav.csv": nav.replace(b"452004,", b"east,", 1)}, r"[\s\S]*nav\.csv:4"),
            ("nav.csv going back in time", {"nav.csv": nav.replace(b"1720000005,", b"1710000005,", 1)}, r"[\s\S]*nav\.csv:7"),
            ("nav.csv with NaN", {"nav.csv": nav.replace(b"452006,4630000,1,", b"452006,4630000,nan,", 1)}, r"[\s\S]*nav\.csv:5: depth: not finite"),
            ("nav.csv with an easting of 1e300", {"nav.csv": nav.replace(b"452040,4630000", b"1e300,4630000", 1)},
             r"[\s\S]*nav\.csv:22: easting: '1e300' m is no projected coordinate"),
            ("nav.csv of NUL bytes", {"nav.csv": b"\0" * 4096}, r"[\s\S]*nav\.csv"),
            ("nav.csv with a header only", {"nav.csv": nav.split(b"\n")[0] + b"\n"}, r"[\s\S]*nav\.csv"),
            ("pings.csv with a line over 64 KiB", {"pings.csv": pings + b"1720000005.5,1,0,1," + b"9" * (70 << 10) + b"\n"},
             r"[\s\S]*pings\.csv:222"),
            ("pings.csv missing a column", {"pings.csv": pings.replace(b",down", b"", 1)}, r"[\s\S]*pings\.csv"),
            ("a ping of 70 000 beams", {"pings.csv": pings + "".join(f"1720000019.75,{b},0,1,20\n" for b in range(70000)).encode()},
             r"[\s\S]*pings\.csv:65757: beam: the ping at time 1720000019.75 has more than 65535 beams"),
            ("pings.csv left out", {"pings.csv": None}, r"[\s\S]*pings\.csv"),
            ("nav.csv left out", {"nav.csv": None}, r"[\s\S]*nav\.csv"),
            ("survey.json not JSON", {"survey.json": b"{name: tiny"}, r"[\s\S]*survey\.json"),
            ("survey.json without a CRS", {"survey.json": b'{"name": "tiny"}'}, r"[\s\S]*survey\.json.*crs"),
            ("survey.json of another CRS", {"survey.json": b'{"name": "tiny", "crs": "EPSG:32652"}'},
             r"[\s\S]*survey\.json.*crs.*'EPSG:32652' but the survey was created with 'EPSG:32651'"),
            ("survey.json nested 100 000 deep", {"survey.json": ('{"name": "t", "crs": "EPSG:32651", "sonar": ' + DEEP + "}").encode()},
             r"[\s\S]*survey\.json: nested deeper than 64 levels"),
            ("survey.json with \\u0000 in a name", {"survey.json": b'{"name": "t\\u0000", "crs": "EPSG:32651"}'},
             r"[\s\S]*survey\.json: a string holds \\u0000"),
            ("survey.json with a number beyond a double", {"survey.json": b'{"name": "t", "crs": "EPSG:32651", "x": 6e524}'},
             r"[\s\S]*survey\.json"),
            ("a survey spanning 500 km", {"nav.csv": nav.replace(b"452040,4630000", b"952040,5130000", 1)},
             r"[\s\S]*nav\.csv: easting, northing: the survey covers \d+ m × \d+ m: a map of \d+ cells at [\d.]+ m,"
             " over the limit of 100000000"),
        ]
        with open(os.path.join(os.environ["ALL_DATA"], "0243_P007_MBES_EM122_20150207_044356_Supporter_GA4430.all"),
                  "rb") as f:
            em122 = f.read()
        flipped = bytearray(em122)
        flipped[em122.index(b"\x02X") + 100] ^= 0x10  # inside the first XYZ 88 datagram's body
        with open(os.path.join(os.environ["XTF_DATA"], "0009_150708_R2Testing_0001.xtf"), "rb") as f:
            r2sonic = f.read()
        first_ping = 1152  # the first bathymetry packet, after the 1024-byte header, a fix and an attitude packet
        lying = bytearray(r2sonic)
        lying[first_ping + 10:first_ping + 14] = (100).to_bytes(4, "little")  # less than its own ping header
        unknown = bytearray(r2sonic)
        unknown[1024] = 0  # the first packet's magic number 0xFACE
        sonar_files = [
            ("an .xtf file cut short", {"r2.xtf": r2sonic[:first_ping + 1000]},
             r"[\s\S]*r2\.xtf:1152: NumBytesThisRecord: 2176 bytes run past the end of the file"),
            ("an .xtf packet whose length lies", {"r2.xtf": bytes(lying)},
             r"[\s\S]*r2\.xtf:1152: R2Sonic bathymetry packet ping header up to SensorYcoordinate: runs past the end"),
            ("an .xtf packet without its magic number", {"r2.xtf": bytes(unknown)},
             r"[\s\S]*r2\.xtf:1024: packet magic number: 0xFA00 is not 0xFACE"),
            ("an .xtf file of another format's bytes", {"r2.xtf": b"\0" * 4096},
             r"[\s\S]*r2\.xtf:0: file header FileFormat: 0 is not 123"),
            ("an .all file cut short", {"em122.all": em122[:100000]},
             r"[\s\S]*em122\.all:\d+: datagram length: \d+ bytes run past the end of the file"),
            ("an .all datagram with a wrong checksum", {"em122.all": bytes(flipped)},
             r"[\s\S]*em122\.all:\d+: checksum: the bytes sum to \d+, the datagram says \d+"),
            ("an .all file of another format's bytes", {"em122.all": b"\0" * 4096},
             r"[\s\S]*em122\.all:0: datagram length: 0 bytes is shorter than a datagram's frame"),
            ("a .gsf and an .all file in one survey", {"a.gsf": b"\0" * 64, "em122.all": em122},
             r"[\s\S]*must be of one format"),
        ]
        finalize = [Case(name, self.finalize_bundle(tiny_bundle(**files)), INVALID, r"survey \d+ is not valid:" + pattern, True)
                    for name, files, pattern in bundles]
        finalize += [Case(name, self.finalize_bundle(files), INVALID, r"survey \d+ is not valid:" + pattern, True)
                     for name, files, pattern in sonar_files]
        return upload + requests + finalize

    def test_the_control_bundle_is_valid(self):
        survey = self.surveys.GetSurvey(survey_pb2.GetSurveyRequest(survey_id=self.ready), timeout=30)
        self.assertEqual(survey.state, survey_pb2.Survey.READY, survey)

    def test_every_hostile_input_is_refused_and_changes_nothing(self):
        cases = self.cases()
        self.assertGreaterEqual(len(cases), 40)
        for case in cases:
            with self.subTest(case.name):
                rows_where = {"survey_validations": "false"} if case.finalize else {}
                before = database_fingerprint(self.server.url, rows_where)
                with self.assertRaises(grpc.RpcError) as raised:
                    case.act(self)
                self.assertIsNone(self.server.process.poll(), "the server died:\n" + self.server.server_log())
                error = raised.exception
                self.assertEqual(error.code(), case.code, error.details())
                self.assertRegex(error.details(), "^" + case.message)
                self.assertNotRegex(error.details(), INTERNALS)
                self.assertEqual(database_fingerprint(self.server.url, rows_where), before, "the database changed")

    def test_the_log_has_one_line_per_event(self):
        """Whatever a client sent (the table's cases again, among them a name that holds a log
        line of its own), every line of the server's log is one event: it starts with its time,
        no line is the forged one, and no terminal escape reaches the log."""
        self.surveys.CreateSurvey(survey_pb2.CreateSurveyRequest(name="log \u00e9t\u00e9"), timeout=30)
        for case in self.cases():
            try:
                case.act(self)
            except grpc.RpcError:
                pass
        lines = self.server.server_log().splitlines()
        self.assertTrue(any("'log \u00e9t\u00e9'" in line for line in lines), "UTF-8 in a name is kept as it is")
        for line in lines:
            self.assertRegex(line, r"^\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z ")
            self.assertNotIn(FORGED_LINE, line[:len(FORGED_LINE)], "a name forged a log line")
            self.assertNotIn("\x1b", line)


class ConcurrentCreateTest(unittest.TestCase):
    """One name created by 12 clients at once: one survey, and every other call ALREADY_EXISTS
    naming the field, whichever of the look-up or the unique index refused it."""

    def test_one_name_created_by_twelve_clients_at_once(self):
        server = Server()
        self.addCleanup(server.stop)

        def create(name):
            try:
                server.surveys.CreateSurvey(survey_pb2.CreateSurveyRequest(name=name), timeout=60)
                return "OK", ""
            except grpc.RpcError as error:
                return error.code().name, error.details()

        with ThreadPoolExecutor(12) as pool:
            for round in range(8):  # the race is won differently each time
                outcomes = list(pool.map(create, [f"race {round}"] * 12))
                codes = [code for code, _ in outcomes]
                self.assertEqual(codes.count("OK"), 1, outcomes)
                for code, details in outcomes:
                    if code != "OK":
                        self.assertEqual(code, "ALREADY_EXISTS", details)
                        self.assertRegex(details, rf"^name: .*'race {round}'")
                        self.assertNotRegex(details, INTERNALS)


if __name__ == "__main__":
    unittest.main(verbosity=2)
