-- Job products as large as the survey (the survey's pings with the corrected navigation as GSF):
-- stored in chunks, as uploaded files are, so that neither storing nor serving one needs the
-- whole file in memory or in one bytea.
CREATE TABLE job_files (
  job_id      bigint NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
  name        text NOT NULL CHECK (name ~ '^[A-Za-z0-9][A-Za-z0-9._-]*$'),
  size_bytes  bigint NOT NULL CHECK (size_bytes >= 0),
  chunk_count integer NOT NULL CHECK (chunk_count >= 0),
  PRIMARY KEY (job_id, name)
);

CREATE TABLE job_file_chunks (
  job_id bigint NOT NULL,
  name   text NOT NULL,
  seq    integer NOT NULL CHECK (seq >= 0),
  data   bytea NOT NULL,
  PRIMARY KEY (job_id, name, seq),
  FOREIGN KEY (job_id, name) REFERENCES job_files (job_id, name) ON DELETE CASCADE
);
