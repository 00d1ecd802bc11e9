-- A tenant's storage quota (issue 37): the bytes its surveys' uploaded files may declare in all,
-- checked when a file is declared; NULL: no quota. `bathyslam-server tenant quota` sets it.
ALTER TABLE tenants ADD COLUMN quota_bytes bigint CHECK (quota_bytes IS NULL OR quota_bytes >= 0);
