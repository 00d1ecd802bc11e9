-- The service (issue 7): survey metadata, resumable uploads, the map frame's origin of a job,
-- the map's description and the tile formats the API serves.

-- What CreateSurvey declares; FinalizeSurvey checks survey.json against it.
ALTER TABLE surveys
  ADD COLUMN crs     text  NOT NULL DEFAULT '',
  ADD COLUMN sonar   jsonb NOT NULL DEFAULT '{}',
  ADD COLUMN vehicle jsonb NOT NULL DEFAULT '{}';

-- A file is uploaded in chunks as they arrive: size_bytes and sha256 are what the client
-- declared, committed_bytes what is stored so far (a cut upload resumes there), and complete
-- is set once the stored bytes matched the declared size and SHA-256.
ALTER TABLE survey_files
  ADD COLUMN committed_bytes bigint,
  ADD COLUMN complete boolean NOT NULL DEFAULT true;
UPDATE survey_files SET committed_bytes = size_bytes;
ALTER TABLE survey_files
  ALTER COLUMN committed_bytes SET NOT NULL,
  ALTER COLUMN complete SET DEFAULT false,
  ADD CHECK (committed_bytes >= 0 AND committed_bytes <= size_bytes),
  ADD CHECK (NOT complete OR committed_bytes = size_bytes);

-- The map frame of a job's poses is the survey's CRS minus this origin.
ALTER TABLE jobs
  ADD COLUMN origin_easting  double precision,
  ADD COLUMN origin_northing double precision;

-- png: rendered tiles; cog: the whole map as one Cloud Optimized GeoTIFF (level 0, tile 0 0).
ALTER TABLE tiles DROP CONSTRAINT tiles_format_check;
ALTER TABLE tiles ADD CONSTRAINT tiles_format_check CHECK (format IN ('geotiff', 'openvdb', 'png', 'cog'));

-- The tile grid of a job's map, written by the tiling stage with its tiles.
CREATE TABLE maps (
  job_id          bigint PRIMARY KEY REFERENCES jobs (id) ON DELETE CASCADE,
  epsg            integer NOT NULL CHECK (epsg > 0),
  resolution_m    double precision NOT NULL CHECK (resolution_m > 0),
  min_easting     double precision NOT NULL,
  min_northing    double precision NOT NULL,
  max_easting     double precision NOT NULL,
  max_northing    double precision NOT NULL,
  tile_size_cells integer NOT NULL CHECK (tile_size_cells > 0),
  levels          integer NOT NULL CHECK (levels > 0)
);
