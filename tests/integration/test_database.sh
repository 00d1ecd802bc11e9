# Sourced by the shell integration tests: a database of their own in the ctest cluster
# ($BATHYSLAM_TEST_PG, made by $PG_SH), a scratch folder, and a cleanup on exit that stops the
# server the test started ($server_pid) and drops both.
db=${1}_$$
admin=$(bash "$PG_SH" url "$BATHYSLAM_TEST_PG")
url=$(bash "$PG_SH" url "$BATHYSLAM_TEST_PG" "$db")
work=$(mktemp -d)
server_pid=""
cleanup() {
  [ -z "$server_pid" ] || { kill "$server_pid" 2> /dev/null || true; wait "$server_pid" 2> /dev/null || true; }
  psql -q "$admin" -c "DROP DATABASE IF EXISTS $db WITH (FORCE)" > /dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
psql -q "$admin" -c "CREATE DATABASE $db" > /dev/null
