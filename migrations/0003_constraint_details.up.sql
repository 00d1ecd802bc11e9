-- What the mchs configuration records of each registration: where its translation is compared
-- (the overlap centroid, in the `to` submap's frame), why the switch chose its path, and the
-- feature statistics behind that choice and behind its information.
ALTER TABLE constraints
  ADD COLUMN anchor          double precision[] NOT NULL DEFAULT '{0,0,0}' CHECK (cardinality(anchor) = 3),
  ADD COLUMN path_reason     text NOT NULL DEFAULT '',
  ADD COLUMN feature_density double precision NOT NULL DEFAULT 0,
  ADD COLUMN matches         integer NOT NULL DEFAULT 0 CHECK (matches >= 0),
  ADD COLUMN inlier_ratio    double precision NOT NULL DEFAULT 0;
