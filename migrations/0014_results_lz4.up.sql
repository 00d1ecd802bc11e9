-- Results compressed by PostgreSQL with LZ4 instead of its default pglz (issue 35), as uploaded
-- chunks are since 0009. Submaps' points are stored as their float32 bytes in planes (every
-- float's first byte, then every second ...; points_encoding 'f32le-planes'): deflating them in
-- the worker took 5.1 of the 6.5 s `lake`'s submaps took to store, on the job's core, for 181 MB;
-- the planes with LZ4 take 1.4 s for 164 MB, in the database's own process. Rows already stored
-- keep their encoding and compression. A server built without LZ4 keeps pglz.
DO $$
BEGIN
  ALTER TABLE submaps ALTER COLUMN points SET COMPRESSION lz4;
  ALTER TABLE job_file_chunks ALTER COLUMN data SET COMPRESSION lz4;
EXCEPTION WHEN feature_not_supported OR invalid_parameter_value THEN
  RAISE NOTICE 'LZ4 is not available: results stay compressed with pglz';
END
$$;

ALTER TABLE submaps DROP CONSTRAINT submaps_points_encoding_check;
ALTER TABLE submaps ADD CONSTRAINT submaps_points_encoding_check
  CHECK (points_encoding IN ('f32le', 'f32le+zlib', 'f32le-planes'));
