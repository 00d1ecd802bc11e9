# Sourced by the bench scripts: a private PostgreSQL cluster and a bathyslam-server on it, both
# removed when the script exits. Needs `root` (the repository) and `build` set; sets `work` (a
# temporary folder), `url` (the database), `server_pid` and BATHYSLAM_SERVER (its address).
#   start_private_server [server options...]   (the database is migrated first)
work=$(mktemp -d /tmp/bathyslam-bench.XXXXXX)
server_pid=""
stop_private_server() {
  [ -z "$server_pid" ] || { kill "$server_pid" 2> /dev/null || true; wait "$server_pid" 2> /dev/null || true; }
  bash "$root/scripts/pg.sh" destroy "$work/pg" > /dev/null 2>&1 || true
  rm -rf "$work"
}
trap stop_private_server EXIT
bash "$root/scripts/pg.sh" start "$work/pg" > /dev/null
url=$(bash "$root/scripts/pg.sh" url "$work/pg")
"$build/server/bathyslam-server" migrate --db "$url" > /dev/null

start_private_server() {
  "$build/server/bathyslam-server" --db "$url" --listen 127.0.0.1:0 --scratch "$work/scratch" "$@" \
    > "$work/server.out" 2> "$work/server.log" &
  server_pid=$!
  for _ in $(seq 100); do grep -q "listening" "$work/server.out" && break; sleep 0.1; done
  BATHYSLAM_SERVER=$(sed -n 's/.*listening on //p' "$work/server.out")
  export BATHYSLAM_SERVER
  [ -n "$BATHYSLAM_SERVER" ] || { cat "$work/server.log" >&2; exit 1; }
}
