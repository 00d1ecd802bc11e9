-- A token may be issued for a limited time: after expires_at it is refused as a revoked one is.
-- NULL: it does not expire.
ALTER TABLE api_tokens ADD COLUMN expires_at timestamptz;
