-- Sites (issue 33): a tenant's surveys of one area, grouped so that one job joins them all.
-- A site holds surveys in the order they were added; the first is the datum of its jobs unless a
-- job names another. Deleting a site leaves its surveys and its jobs; deleting a survey takes
-- it out of every site.
CREATE TABLE sites (
  id         bigint GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  tenant_id  bigint NOT NULL REFERENCES tenants (id) ON DELETE CASCADE,
  name       text NOT NULL CHECK (name <> ''),
  created_at timestamptz NOT NULL DEFAULT now(),
  UNIQUE (tenant_id, name)  -- also the index for a tenant's sites
);

CREATE TABLE site_surveys (
  site_id   bigint NOT NULL REFERENCES sites (id) ON DELETE CASCADE,
  position  integer NOT NULL CHECK (position >= 0),
  survey_id bigint NOT NULL REFERENCES surveys (id) ON DELETE CASCADE,
  PRIMARY KEY (site_id, position),
  UNIQUE (site_id, survey_id)
);
CREATE INDEX site_surveys_survey ON site_surveys (survey_id);

-- The site a job was submitted for, kept for listing (its surveys are in job_surveys as before).
ALTER TABLE jobs ADD COLUMN site_id bigint REFERENCES sites (id) ON DELETE SET NULL;
CREATE INDEX jobs_site ON jobs (site_id) WHERE site_id IS NOT NULL;
