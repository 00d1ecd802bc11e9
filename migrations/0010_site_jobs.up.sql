-- Jobs of several surveys of one site (issue 33): a job's survey_id is its first survey, the
-- datum; the others follow in the order given, joined in one graph. A job's datum edges (the
-- later surveys' starts held to the first's by both start fixes) are constraints of type 'datum'.
CREATE TABLE job_surveys (
  job_id    bigint NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
  position  integer NOT NULL CHECK (position >= 1),  -- 0 is jobs.survey_id
  survey_id bigint NOT NULL REFERENCES surveys (id),
  PRIMARY KEY (job_id, position),
  UNIQUE (job_id, survey_id)
);
CREATE INDEX job_surveys_survey ON job_surveys (survey_id);

ALTER TABLE constraints DROP CONSTRAINT constraints_type_check;
ALTER TABLE constraints ADD CONSTRAINT constraints_type_check CHECK (type IN ('odometry', 'adjacent', 'loop', 'datum'));
