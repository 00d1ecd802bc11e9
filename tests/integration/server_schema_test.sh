#!/usr/bin/env bash
# bathyslam-server against the private cluster: `migrate` applies the schema once; the server
# refuses to start on a schema that is behind (unless --migrate) or ahead of it.
set -euo pipefail
source "$(dirname "$0")/test_database.sh" server_schema

expect_refusal() {  # expect_refusal PATTERN ARGS...: the server exits non-zero saying PATTERN
  local pattern=$1
  shift
  if timeout 20 "$BATHYSLAM_SERVER" "$@" > "$work/out" 2> "$work/err"; then
    echo "server started with $*" >&2
    exit 1
  fi
  grep -q "$pattern" "$work/err" || { echo "expected '$pattern', got:" >&2; cat "$work/err" >&2; exit 1; }
}

expect_refusal "no database" --listen 127.0.0.1:0
expect_refusal "run \`bathyslam-server migrate\`" --db "$url" --listen 127.0.0.1:0

"$BATHYSLAM_SERVER" migrate --db "$url" > "$work/first"
grep -q "^applied migration 0001$" "$work/first"
BATHYSLAM_DB="$url" "$BATHYSLAM_SERVER" migrate > "$work/second"
grep -q "(0 applied)" "$work/second"
[ "$(psql -At "$url" -c "SELECT count(*) FROM schema_migrations")" = "$(grep -c '^applied migration' "$work/first")" ]

# Up to date: it starts and serves until told to stop.
"$BATHYSLAM_SERVER" --db "$url" --listen 127.0.0.1:0 > "$work/serve" 2>&1 &
server_pid=$!
for _ in $(seq 100); do grep -q "listening" "$work/serve" && break; sleep 0.1; done
grep -q "listening" "$work/serve" || { cat "$work/serve" >&2; exit 1; }
kill -TERM "$server_pid"
wait "$server_pid"
server_pid=""

# A schema from a newer release: refused, with or without --migrate, and migrate refuses too.
latest=$(psql -At "$url" -c "SELECT max(version) FROM schema_migrations")
psql -q "$url" -c "INSERT INTO schema_migrations (version, name) VALUES ($((latest + 1)), 'future')"
expect_refusal "newer than this server knows" --db "$url" --listen 127.0.0.1:0
expect_refusal "newer than this server knows" --db "$url" --migrate --listen 127.0.0.1:0
expect_refusal "newer than this binary" migrate --db "$url"
echo "server schema: ok"
