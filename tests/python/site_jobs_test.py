#!/usr/bin/env python3
"""Jobs of several surveys of one site (issue 33) against a real server and PostgreSQL: two
epochs of `small` joined in one `mchs` job, stored and served like a single survey's job (its
report's site section, the difference map by GetMap, the datum edge among its constraints), and
every refusal of a survey list (another tenant's survey, a survey twice, one not ready, another CRS,
too many) answered naming the field with the database unchanged. The same environment as
service_api_test.py (set by ctest)."""
import json
import os
import subprocess
import unittest

import grpc
from osgeo import gdal

from http_api_test import HttpServer
from service_api_test import STUBS, database_fingerprint, job_pb2, psql, restart_asking_for_tokens, site_pb2, survey_pb2

import bathyslam  # noqa: E402  (the Python client, on the path service_api_test puts)

gdal.UseExceptions()


def simulate_epoch(epoch):
    out = os.path.join(STUBS, f"site-epoch{epoch}")
    if not os.path.exists(os.path.join(out, "survey.json")):
        subprocess.run([os.environ["BATHYSLAM"], "simulate", "--scenario", "small", "--seed", "1", "--epoch", str(epoch),
                        "--out", out], check=True, capture_output=True)
    return out


class SiteJobsTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.server = HttpServer(dev_tenant="owner")
        with bathyslam.Client(cls.server.address) as client:
            cls.first = client.upload(simulate_epoch(1))
            cls.second = client.upload(simulate_epoch(2))
            cls.single = client.submit(cls.first, "odometry")
            client.watch(cls.single)
        cls.tokens = restart_asking_for_tokens(cls.server)
        cls.owner = bathyslam.Client(cls.server.address, cls.tokens["owner"])
        cls.intruder = bathyslam.Client(cls.server.address, cls.tokens["another tenant"])

    @classmethod
    def tearDownClass(cls):
        cls.owner.close()
        cls.intruder.close()
        if os.environ.get("SHOW_SERVER_LOG"):
            print(cls.server.server_log())
        cls.server.stop()

    def refused(self, client, more, code, message, survey=None):
        before = database_fingerprint(self.server.url)
        with self.assertRaises(bathyslam.BathyslamError) as raised:
            client.submit(survey or self.first, "mchs", more_survey_ids=more)
        self.assertEqual(raised.exception.code, code, raised.exception)
        self.assertRegex(str(raised.exception), message)
        self.assertEqual(database_fingerprint(self.server.url), before, f"{more}: the database changed")

    def test_refusals_name_the_field_and_change_nothing(self):
        self.refused(self.owner, [self.first], grpc.StatusCode.INVALID_ARGUMENT,
                     rf"more_survey_ids\[0\]: survey {self.first} is already in the job")
        self.refused(self.owner, [self.second, self.second], grpc.StatusCode.INVALID_ARGUMENT,
                     rf"more_survey_ids\[1\]: survey {self.second} is already in the job")
        self.refused(self.owner, [self.second, 999999], grpc.StatusCode.NOT_FOUND, r"more_survey_ids\[1\]: no survey 999999")
        self.refused(self.owner, list(range(1000, 1020)), grpc.StatusCode.INVALID_ARGUMENT,
                     r"more_survey_ids: 20 surveys; a job joins at most 20")
        # Another tenant: neither its own job with the owner's survey, nor one of the owner's.
        theirs = self.intruder._call("CreateSurvey", self.intruder._surveys.CreateSurvey,
                                     survey_pb2.CreateSurveyRequest(name="theirs", crs="EPSG:32651")).id
        self.refused(self.owner, [theirs], grpc.StatusCode.NOT_FOUND, rf"more_survey_ids\[0\]: no survey {theirs}")
        self.refused(self.intruder, [self.second], grpc.StatusCode.NOT_FOUND, rf"survey_id: no survey {self.first}")
        # Not ready, and another CRS.
        empty = self.owner._call("CreateSurvey", self.owner._surveys.CreateSurvey,
                                 survey_pb2.CreateSurveyRequest(name="not ready", crs="EPSG:32651")).id
        self.refused(self.owner, [empty], grpc.StatusCode.FAILED_PRECONDITION, rf"more_survey_ids\[0\]: survey {empty} is not ready")
        psql(self.server.url, f"UPDATE surveys SET crs = 'EPSG:32650' WHERE id = {self.second}")
        try:
            self.refused(self.owner, [self.second], grpc.StatusCode.INVALID_ARGUMENT,
                         rf"more_survey_ids\[0\]: survey {self.second} is in EPSG:32650, survey {self.first} in EPSG:32651")
        finally:
            psql(self.server.url, f"UPDATE surveys SET crs = 'EPSG:32651' WHERE id = {self.second}")

    def assert_refused(self, call, code, message):
        before = database_fingerprint(self.server.url)
        with self.assertRaises(bathyslam.BathyslamError) as raised:
            call()
        self.assertEqual(raised.exception.code, code, raised.exception)
        self.assertRegex(str(raised.exception), message)
        self.assertEqual(database_fingerprint(self.server.url), before, "a refusal changed the database")

    def test_site_groups_surveys_for_a_job(self):
        site = self.owner.create_site("harbour")
        self.assert_refused(lambda: self.owner.create_site("harbour"), grpc.StatusCode.ALREADY_EXISTS,
                            rf"name: site {site} is named 'harbour' already")
        self.assertEqual(self.owner.add_surveys(site, [self.first, self.second])["survey_ids"], [self.first, self.second])
        self.assert_refused(lambda: self.owner.add_surveys(site, [self.first]), grpc.StatusCode.INVALID_ARGUMENT,
                            rf"survey_ids\[0\]: survey {self.first} is in site {site} already")
        theirs = self.intruder._call("CreateSurvey", self.intruder._surveys.CreateSurvey,
                                     survey_pb2.CreateSurveyRequest(name="their site survey", crs="EPSG:32651")).id
        self.assert_refused(lambda: self.owner.add_surveys(site, [theirs]), grpc.StatusCode.NOT_FOUND,
                            rf"survey_ids\[0\]: no survey {theirs}")
        self.assert_refused(lambda: self.intruder.submit(site_id=site), grpc.StatusCode.NOT_FOUND, rf"site_id: no site {site}")
        self.assert_refused(lambda: self.intruder.site(site), grpc.StatusCode.NOT_FOUND, rf"site_id: no site {site}")
        remove = lambda ids: self.owner._call("RemoveSurveys", self.owner._sites.RemoveSurveys,  # noqa: E731
                                              site_pb2.RemoveSurveysRequest(site_id=site, survey_ids=ids))
        self.assert_refused(lambda: remove([self.second, self.second]), grpc.StatusCode.INVALID_ARGUMENT,
                            rf"survey_ids\[1\]: survey {self.second} is named twice")
        self.assert_refused(lambda: remove([theirs]), grpc.StatusCode.INVALID_ARGUMENT,
                            rf"survey_ids\[0\]: survey {theirs} is not in site {site}")
        self.assert_refused(lambda: self.owner.submit(self.first, site_id=site), grpc.StatusCode.INVALID_ARGUMENT,
                            r"site_id: a job names a site or its surveys")
        self.assert_refused(lambda: self.owner.submit(site_id=site, reference_survey_id=999999),
                            grpc.StatusCode.INVALID_ARGUMENT, r"reference_survey_id: survey 999999 is not one of")
        # The second survey held in place: it is the job's datum and the first comes after it.
        job = self.owner.submit(site_id=site, config="odometry", reference_survey_id=self.second)
        described = self.owner.job(job)
        self.assertEqual((described["survey_id"], described["more_survey_ids"], described["site_id"]),
                         (self.second, [self.first], site))
        self.assertEqual(self.owner.watch(job)["state"], "succeeded")
        listed = self.owner._call("ListJobs", self.owner._jobs.ListJobs, job_pb2.ListJobsRequest(site_id=site)).jobs
        self.assertEqual([j.id for j in listed], [job])
        connection = self.server.connection()  # and over HTTP
        connection.request("GET", f"/v1/jobs?site_id={site}", headers={"Authorization": "Bearer " + self.tokens["owner"]})
        self.assertEqual([(j["id"], j["site_id"]) for j in json.loads(connection.getresponse().read())["jobs"]], [(job, site)])
        connection.close()
        by_later_survey = self.owner._call("ListJobs", self.owner._jobs.ListJobs, job_pb2.ListJobsRequest(survey_id=self.first))
        self.assertIn(job, [j.id for j in by_later_survey.jobs], "a job is listed under each of its surveys")
        # Each survey's own corrected GSF, its pings at that survey's corrected navigation.
        gsfs = [self.owner.download_map(job, os.path.join(STUBS, f"site-{k}.gsf"), format="gsf", epoch=k) for k in (1, 2)]
        for path, survey in zip(gsfs, (self.second, self.first)):
            inspected = subprocess.run([os.environ["BATHYSLAM"], "inspect", path, "--crs", "EPSG:32651", "--json"],
                                       check=True, capture_output=True, text=True).stdout
            summary = json.loads(self.owner._call("GetSurvey", self.owner._surveys.GetSurvey,
                                                  survey_pb2.GetSurveyRequest(survey_id=survey)).summary_json)
            pings, expected = json.loads(inspected)["survey"]["counts"]["pings"], summary["counts"]["pings"]
            # Pings beyond the corrected navigation's ends are left out: a few at most.
            self.assertLessEqual(abs(pings - expected), 0.01 * expected, path)
        with self.assertRaises(bathyslam.BathyslamError) as raised:
            self.owner.download_map(job, os.path.join(STUBS, "x.gsf"), format="gsf", epoch=3)
        self.assertRegex(str(raised.exception), r"survey: 3 is not a survey of job \d+ \(1 to 2\)")
        # Deleting the site leaves its surveys and jobs.
        self.owner._call("DeleteSite", self.owner._sites.DeleteSite, site_pb2.DeleteSiteRequest(site_id=site))
        self.assertEqual(self.owner.job(job)["site_id"], 0)
        self.assertEqual(self.owner.job(job)["state"], "succeeded")

    def test_two_epochs_in_one_job(self):
        job = self.owner.submit(self.first, "mchs", more_survey_ids=[self.second])
        self.assertEqual(self.owner.job(job)["more_survey_ids"], [self.second])
        self.assertEqual(self.owner.watch(job)["state"], "succeeded")
        report = self.owner.report(job)
        site = report["site"]
        self.assertEqual([s["submaps"] for s in site["surveys"]][0], site["surveys"][1]["first_submap"])
        self.assertGreater(site["surveys"][1]["registrations_with_other_surveys"]["accepted"], 0)
        across = site["consistency_error_m"]["across_surveys"]
        self.assertLess(across["optimized"]["rmse"], 0.5 * across["dead_reckoning"]["rmse"])
        difference = site["differences"][0]
        self.assertEqual((difference["before"], difference["after"], difference["file"]), (1, 2, "difference_1_2.tif"))
        self.assertGreater(difference["cells_compared"], 1000)
        self.assertLess(abs(difference["changed_areas"][0]["largest_change_m"] + 0.3), 0.1, "the dredged area")
        # The difference map as a GeoTIFF GDAL reads; a survey that is not in the job is refused.
        path = self.owner.download_map(job, os.path.join(STUBS, "difference.tif"), format="difference", epoch=2)
        tif = gdal.Open(path)
        self.assertEqual([tif.GetRasterBand(b).GetDescription() for b in range(1, 5)],
                         ["change", "sigma", "significant", "local_offset"])
        connection = self.server.connection()  # the same bytes over HTTP
        connection.request("GET", f"/v1/jobs/{job}/difference_1_2.tif", headers={"Authorization": "Bearer " + self.tokens["owner"]})
        response = connection.getresponse()
        with open(path, "rb") as f:
            self.assertEqual((response.status, response.read()), (200, f.read()))
        connection.close()
        with self.assertRaises(bathyslam.BathyslamError) as raised:
            self.owner.download_map(job, os.path.join(STUBS, "x.tif"), format="difference", epoch=3)
        self.assertRegex(str(raised.exception), r"epoch: 3 is not a later survey of job \d+ \(2 to 2\)")
        with self.assertRaises(bathyslam.BathyslamError) as raised:
            self.owner.download_map(job, os.path.join(STUBS, "x.tif"), format="difference", epoch=2, from_epoch=2)
        self.assertRegex(str(raised.exception), r"from_epoch: 2 is not an earlier survey of job \d+ \(1 to 1\)")
        with self.assertRaises(bathyslam.BathyslamError) as raised:
            self.owner.download_map(self.single, os.path.join(STUBS, "x.tif"), format="difference")
        self.assertRegex(str(raised.exception), r"format: job \d+ has one survey")
        # Stored like any job: its datum edge among the constraints, and listed with its first survey.
        self.assertEqual(psql(self.server.url, f"SELECT count(*) FROM constraints WHERE job_id = {job} AND type = 'datum'"), "1")
        with self.assertRaises(bathyslam.BathyslamError):
            self.intruder.download_map(job, os.path.join(STUBS, "x.tif"), format="difference")
        # Deleting the second survey takes the job with it.
        self.owner._call("DeleteSurvey", self.owner._surveys.DeleteSurvey, survey_pb2.DeleteSurveyRequest(survey_id=self.second))
        self.assertEqual(psql(self.server.url, f"SELECT count(*) FROM jobs WHERE id = {job}"), "0")
        self.assertEqual(psql(self.server.url, f"SELECT count(*) FROM jobs WHERE id = {self.single}"), "1")


if __name__ == "__main__":
    unittest.main(verbosity=2)
