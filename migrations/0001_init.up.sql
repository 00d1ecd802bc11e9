-- The first schema: everything a survey's processing reads or writes. Deleting a survey removes
-- everything under it (ON DELETE CASCADE all the way down); a tenant's deletion removes its
-- surveys and tokens.

CREATE TABLE tenants (
  id         bigint GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  name       text NOT NULL UNIQUE CHECK (name <> ''),
  created_at timestamptz NOT NULL DEFAULT now()
);

-- Only the SHA-256 of a token is kept: tokens are 256-bit random, so a fast hash is enough and a
-- leaked table does not leak credentials.
CREATE TABLE api_tokens (
  id           bigint GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  tenant_id    bigint NOT NULL REFERENCES tenants (id) ON DELETE CASCADE,
  token_sha256 bytea NOT NULL UNIQUE CHECK (length(token_sha256) = 32),
  description  text NOT NULL DEFAULT '',
  created_at   timestamptz NOT NULL DEFAULT now(),
  revoked_at   timestamptz
);
CREATE INDEX api_tokens_tenant ON api_tokens (tenant_id);

CREATE TABLE surveys (
  id         bigint GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  tenant_id  bigint NOT NULL REFERENCES tenants (id) ON DELETE CASCADE,
  name       text NOT NULL CHECK (name <> ''),
  created_at timestamptz NOT NULL DEFAULT now(),
  UNIQUE (tenant_id, name)  -- also the index for a tenant's surveys
);

-- Uploaded files are stored in chunks so that neither an upload nor a download needs the whole
-- file in one message or one bytea (a lake survey's pings.csv is about a gigabyte).
CREATE TABLE survey_files (
  id          bigint GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  survey_id   bigint NOT NULL REFERENCES surveys (id) ON DELETE CASCADE,
  name        text NOT NULL CHECK (name ~ '^[A-Za-z0-9][A-Za-z0-9._-]*$'),
  size_bytes  bigint NOT NULL CHECK (size_bytes >= 0),
  sha256      bytea NOT NULL CHECK (length(sha256) = 32),
  chunk_count integer NOT NULL CHECK (chunk_count >= 0),
  created_at  timestamptz NOT NULL DEFAULT now(),
  UNIQUE (survey_id, name)
);

CREATE TABLE survey_file_chunks (
  file_id bigint NOT NULL REFERENCES survey_files (id) ON DELETE CASCADE,
  seq     integer NOT NULL CHECK (seq >= 0),
  data    bytea NOT NULL,
  PRIMARY KEY (file_id, seq)
);

-- The latest validation of a survey's bundle: every problem as {file, line, field, message}.
CREATE TABLE survey_validations (
  survey_id    bigint PRIMARY KEY REFERENCES surveys (id) ON DELETE CASCADE,
  valid        boolean NOT NULL,
  problems     jsonb NOT NULL DEFAULT '[]',
  summary      jsonb,
  validated_at timestamptz NOT NULL DEFAULT now()
);

CREATE TABLE jobs (
  id               bigint GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  survey_id        bigint NOT NULL REFERENCES surveys (id) ON DELETE CASCADE,
  configuration    text NOT NULL CHECK (configuration IN ('odometry', 'gicp', 'mchs')),
  parameters       jsonb NOT NULL DEFAULT '{}',  -- the effective configuration, every parameter
  state            text NOT NULL DEFAULT 'queued'
                   CHECK (state IN ('queued', 'running', 'succeeded', 'failed', 'cancelled')),
  attempts         integer NOT NULL DEFAULT 0 CHECK (attempts >= 0),
  max_attempts     integer NOT NULL DEFAULT 3 CHECK (max_attempts >= 1),
  worker           text,
  lease_expires_at timestamptz,
  heartbeat_at     timestamptz,
  error            text,
  created_at       timestamptz NOT NULL DEFAULT now(),
  started_at       timestamptz,
  finished_at      timestamptz,
  -- worker: the last one to claim the job (kept after it finishes, for the record)
  CHECK (state <> 'running' OR (worker IS NOT NULL AND lease_expires_at IS NOT NULL))
);
CREATE INDEX jobs_survey ON jobs (survey_id);
-- The claim's lookup and the reaper's: small partial indexes over the few live jobs.
CREATE INDEX jobs_queued ON jobs (id) WHERE state = 'queued';
CREATE INDEX jobs_lease ON jobs (lease_expires_at) WHERE state = 'running';

CREATE TABLE job_events (
  id       bigint GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  job_id   bigint NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
  attempt  integer NOT NULL,
  stage    text NOT NULL,
  progress double precision NOT NULL CHECK (progress >= 0 AND progress <= 1),
  message  text NOT NULL DEFAULT '',
  at       timestamptz NOT NULL DEFAULT clock_timestamp()
);
CREATE INDEX job_events_job ON job_events (job_id, id);

-- Results hang off the job that produced them. Poses are quaternion (w, x, y, z) + translation.
CREATE TABLE submaps (
  job_id          bigint NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
  idx             integer NOT NULL CHECK (idx >= 0),
  line            integer NOT NULL CHECK (line >= -1),
  time_begin      double precision NOT NULL,
  time_mid        double precision NOT NULL,
  time_end        double precision NOT NULL,
  dr_pose         double precision[] NOT NULL CHECK (cardinality(dr_pose) = 7),
  reference_pose  double precision[] CHECK (cardinality(reference_pose) = 7),
  footprint       polygon NOT NULL,  -- DR footprint in the map frame, for spatial lookups
  point_count     integer NOT NULL CHECK (point_count >= 0),
  points_encoding text NOT NULL CHECK (points_encoding IN ('f32le', 'f32le+zlib')),
  points          bytea NOT NULL,
  PRIMARY KEY (job_id, idx)
);
CREATE INDEX submaps_footprint ON submaps USING gist (footprint);

CREATE TABLE constraints (
  job_id           bigint NOT NULL,
  idx              integer NOT NULL CHECK (idx >= 0),
  type             text NOT NULL CHECK (type IN ('odometry', 'adjacent', 'loop')),
  path             text CHECK (path IN ('direct', 'feature-aided')),  -- NULL for odometry
  from_submap      integer NOT NULL,
  to_submap        integer NOT NULL,
  measured         double precision[] NOT NULL CHECK (cardinality(measured) = 7),
  information      double precision[] NOT NULL CHECK (cardinality(information) = 36),  -- row-major 6x6
  converged        boolean NOT NULL,
  fitness          double precision NOT NULL,
  overlap_points   bigint NOT NULL CHECK (overlap_points >= 0),
  overlap_mse_m2   double precision NOT NULL,
  overlap_fraction double precision NOT NULL,
  accepted         boolean NOT NULL,
  reason           text NOT NULL DEFAULT '',
  PRIMARY KEY (job_id, idx),
  FOREIGN KEY (job_id, from_submap) REFERENCES submaps (job_id, idx) ON DELETE CASCADE,
  FOREIGN KEY (job_id, to_submap) REFERENCES submaps (job_id, idx) ON DELETE CASCADE
);
-- Cascading a submap's deletion looks constraints up by either end.
CREATE INDEX constraints_from ON constraints (job_id, from_submap);
CREATE INDEX constraints_to ON constraints (job_id, to_submap);

CREATE TABLE optimized_poses (
  job_id bigint NOT NULL,
  submap integer NOT NULL,
  pose   double precision[] NOT NULL CHECK (cardinality(pose) = 7),
  PRIMARY KEY (job_id, submap),
  FOREIGN KEY (job_id, submap) REFERENCES submaps (job_id, idx) ON DELETE CASCADE
);

CREATE TABLE tiles (
  job_id   bigint NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
  format   text NOT NULL CHECK (format IN ('geotiff', 'openvdb')),
  level    integer NOT NULL CHECK (level >= 0),
  tile_col integer NOT NULL,
  tile_row integer NOT NULL,
  data     bytea NOT NULL,
  PRIMARY KEY (job_id, format, level, tile_col, tile_row)
);

CREATE TABLE reports (
  job_id     bigint PRIMARY KEY REFERENCES jobs (id) ON DELETE CASCADE,
  report     jsonb NOT NULL,
  created_at timestamptz NOT NULL DEFAULT now()
);

CREATE TABLE report_plots (
  job_id bigint NOT NULL REFERENCES reports (job_id) ON DELETE CASCADE,
  name   text NOT NULL CHECK (name ~ '^[A-Za-z0-9][A-Za-z0-9._-]*$'),
  png    bytea NOT NULL,
  PRIMARY KEY (job_id, name)
);
