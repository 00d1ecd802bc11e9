#!/usr/bin/env bash
# The README's main-job command: the whole product on this machine. Builds, starts a private
# PostgreSQL (scripts/pg.sh) and bathyslam-server, simulates the `small` survey, uploads it,
# runs an `mchs` job, watches it, saves the report and the map
# tiles, reads the map over the HTTP endpoint with GDAL, prints where they are, and stops the
# server and PostgreSQL.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
out=${BATHYSLAM_DEMO_DIR:-demo}
mkdir -p "$out"
bin=./build
pg="$out/pg"

bash scripts/pg.sh start "$pg" > /dev/null
url=$(bash scripts/pg.sh url "$pg")
server_pid=""
stop() {
  [ -z "$server_pid" ] || { kill "$server_pid" 2> /dev/null || true; wait "$server_pid" 2> /dev/null || true; }
  bash scripts/pg.sh stop "$pg" > /dev/null || true
}
trap stop EXIT
"$bin/server/bathyslam-server" --db "$url" --migrate --listen 127.0.0.1:0 --http 127.0.0.1:0 --workers 1 --dev-tenant demo \
  > "$out/server.out" 2> "$out/server.log" &
server_pid=$!
for _ in $(seq 100); do grep -q "listening" "$out/server.out" && break; sleep 0.1; done
BATHYSLAM_SERVER=$(sed -n 's/.*listening on //p' "$out/server.out")
[ -n "$BATHYSLAM_SERVER" ] || { cat "$out/server.log" >&2; exit 1; }
export BATHYSLAM_SERVER
http=$(sed -n 's/.*http on //p' "$out/server.out")

"$bin/client/bathyslam" simulate --scenario small --seed 1 --drift paper --out "$out/small"
"$bin/client/bathyslam" inspect --json "$out/small" > "$out/small-summary.json"
survey=$("$bin/client/bathyslam" upload "$out/small" | awk '/^survey/ {print $2}')
job=$("$bin/client/bathyslam" submit "$survey" --config mchs | awk '/^job/ {print $2}')
"$bin/client/bathyslam" watch "$job"
mkdir -p "$out/job-$job"
"$bin/client/bathyslam" report "$job" --out "$out/job-$job" | tee "$out/job-$job/report.txt"
"$bin/client/bathyslam" tiles "$job" --out "$out/job-$job/tiles"
"$bin/client/bathyslam" map "$job" --out "$out/job-$job/map.tif"
# The same map as GIS tools read it from the server: a COG over HTTP range requests.
echo
echo "gdalinfo /vsicurl/$http/v1/jobs/$job/map.tif"
GDAL_DISABLE_READDIR_ON_OPEN=EMPTY_DIR gdalinfo "/vsicurl/$http/v1/jobs/$job/map.tif" | sed -n '1,2p;/Size is/p;/Pixel Size/p'
echo
echo "bundle:      $out/small (summary $out/small-summary.json)"
echo "report:      $out/job-$job (report.txt, report.json, *.png)"
echo "tiles:       $out/job-$job/tiles/{level}/{col}_{row}.tif; whole map $out/job-$job/map.tif"
echo "server log:  $out/server.log; database: $pg (bash scripts/pg.sh start $pg to look inside)"
echo "web page:    $http/#job=$job while a server runs (this one stops now; see README, HTTP)"
