#!/usr/bin/env bash
# A job's reading of its survey in the service, timed: the bundle uploaded once to a private
# server, then the same job run RUNS times by each server binary given, alternately, on the same
# database. Per job, from its events: the load stage (the survey read into submaps), the corrected
# GSF (the survey read again) and the whole job, and the server's peak RSS.
#   bench/job_read.sh BUNDLE BUILD RUNS [CONFIG] [OTHER_SERVER_BINARY]
# CONFIG defaults to odometry (no registrations: the reading is most of the job).
set -euo pipefail
bundle=$(realpath "$1") build=$(realpath "$2") runs=${3:-3} config=${4:-odometry} other=${5:-}
root=$(cd "$(dirname "$0")/.." && pwd)
source "$root/bench/private_server.sh"
psql=$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -n 1)/psql
servers=("$build/server/bathyslam-server")
[ -z "$other" ] || servers+=("$(realpath "$other")")

start_private_server --workers 1 --dev-tenant bench
"$build/client/bathyslam" upload "$bundle" --name job-read > "$work/upload.out" 2> "$work/upload.err"
survey=$(awk '/^survey .* ready$/ {print $2}' "$work/upload.out")
stop_server() { kill "$server_pid"; wait "$server_pid" 2> /dev/null || true; server_pid=""; }
stop_server

# Seconds from a job's first event of stage A at progress at least P to its first of stage B at
# progress at least Q.
between() {
  "$psql" "$url" -At -c "SELECT round(extract(epoch FROM
    (SELECT min(at) FROM job_events WHERE job_id = $1 AND stage = '$4' AND progress >= $5)
    - (SELECT min(at) FROM job_events WHERE job_id = $1 AND stage = '$2' AND progress >= $3))::numeric, 2)"
}
for run in $(seq "$runs"); do
  for server in "${servers[@]}"; do
    "$server" --db "$url" --listen 127.0.0.1:0 --scratch "$work/scratch" --workers 1 --dev-tenant bench \
      > "$work/server.out" 2> "$work/server.log" &
    server_pid=$!
    for _ in $(seq 100); do grep -q "listening" "$work/server.out" && break; sleep 0.1; done
    BATHYSLAM_SERVER=$(sed -n 's/.*listening on //p' "$work/server.out")
    export BATHYSLAM_SERVER
    job=$("$build/client/bathyslam" submit "$survey" --config "$config" | awk '/^job/ {print $2}')
    "$build/client/bathyslam" watch "$job" > /dev/null 2>&1
    rss=$(awk '/VmHWM/ {print $2 / 1024}' "/proc/$server_pid/status")
    stop_server
    echo "run $run $(basename "$server"): job $job load $(between "$job" load 0 load 1) s," \
      "corrected GSF $(between "$job" map 0.5 store 0) s, whole $(between "$job" load 0 done 1) s, server peak RSS ${rss} MB"
  done
done
