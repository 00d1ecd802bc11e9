-- The whole map as BAG (Bathymetry Attributed Grid) beside the COG: stored as tile format 'bag'
-- at level 0, column 0, row 0, as 'cog' is.
ALTER TABLE tiles DROP CONSTRAINT tiles_format_check;
ALTER TABLE tiles ADD CONSTRAINT tiles_format_check CHECK (format IN ('geotiff', 'openvdb', 'png', 'cog', 'bag'));
