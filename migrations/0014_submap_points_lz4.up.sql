-- Submaps' points stored as plain float32 triples and compressed by PostgreSQL with LZ4 (issue
-- 35): deflating them in the worker took 5.1 of the 6.5 s `lake`'s submaps took to store, one
-- core, for 16 % (215 -> 181 MB); LZ4 runs in the database's own process. Rows already stored
-- keep their encoding (points_encoding says which). A server built without LZ4 keeps pglz.
DO $$
BEGIN
  ALTER TABLE submaps ALTER COLUMN points SET COMPRESSION lz4;
EXCEPTION WHEN feature_not_supported OR invalid_parameter_value THEN
  RAISE NOTICE 'LZ4 is not available: submap points stay compressed with pglz';
END
$$;

ALTER TABLE submaps DROP CONSTRAINT submaps_points_encoding_check;
ALTER TABLE submaps ADD CONSTRAINT submaps_points_encoding_check
  CHECK (points_encoding IN ('f32le', 'f32le+zlib', 'f32le-planes'));
