#!/usr/bin/env bash
# Issue 35, jobs that resume: two servers on one private database. The first runs an `mchs` job on
# BUNDLE and is killed outright (SIGKILL) once the job's register stage is FRACTION done; the
# second takes the job over when the lease expires, takes up the registered batches the first
# stored, and finishes it. The same survey is then run again undisturbed on the second server,
# and the two jobs' optimized poses compared. Prints each attempt's time from the servers' logs
# and the figures of the issue: the takeover's attempt against the undisturbed run.
#   bench/kill_resume.sh BUNDLE [FRACTION (0.75)] [BUILD_DIR]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bundle=$(cd "$1" && pwd)
fraction=${2:-0.75}
build=$(cd "${3:-$root/build}" && pwd)
source "$root/bench/private_server.sh"
lease=10
start_private_server --workers 1 --dev-tenant bench --lease-seconds "$lease"
first_pid=$server_pid
cli="$build/client/bathyslam"
q() { psql -qAt "$url" -c "$1"; }

survey=$("$cli" upload "$bundle" --name resume 2> /dev/null | awk '/^survey/ {print $2}')
job=$("$cli" submit "$survey" --config mchs | awk '/^job/ {print $2}')
echo "survey $survey uploaded; job $job submitted"
until [ "$(q "SELECT count(*) FROM job_events WHERE job_id = $job AND stage = 'register' AND progress >= $fraction")" != 0 ]; do
  [ "$(q "SELECT state FROM jobs WHERE id = $job")" = running ] || { q "SELECT state, error FROM jobs WHERE id = $job"; exit 1; }
  sleep 0.2
done
kill -9 "$first_pid"
killed=$(date +%s.%N)
wait "$first_pid" 2> /dev/null || true
batches=$(q "SELECT count(*) FROM job_checkpoints WHERE job_id = $job")
echo "first server killed at register $fraction with $batches batches stored"
mv "$work/server.log" "$work/first.log"

server_pid=""
start_private_server --workers 1 --dev-tenant bench --lease-seconds "$lease"
until [[ "$(q "SELECT state FROM jobs WHERE id = $job")" =~ ^(succeeded|failed)$ ]]; do sleep 0.5; done
finished=$(date +%s.%N)
[ "$(q "SELECT state FROM jobs WHERE id = $job")" = succeeded ] || { q "SELECT error FROM jobs WHERE id = $job"; exit 1; }
again=$("$cli" submit "$survey" --config mchs | awk '/^job/ {print $2}')
"$cli" watch "$again" > /dev/null 2>&1
grep -E "job ($job|$again): (took up|succeeded)" "$work/server.log" | sed 's/^[^ ]* //'
seconds() { sed -n "s/.*job $1: succeeded in \([0-9.]*\) s.*/\1/p" "$work/server.log"; }
# Each stage's time in the two finishing attempts, from their progress events (the next stage's
# first event minus this one's); the store's steps (its events' messages) apart.
stages="SELECT string_agg(format('%s %s s', step, round(seconds::numeric, 1)), ', ' ORDER BY first) FROM (
  SELECT step, min(at) AS first,
         extract(epoch FROM coalesce(lead(min(at)) OVER (ORDER BY min(at)), max(max(at)) OVER ()) - min(at)) AS seconds
  FROM (SELECT CASE WHEN stage = 'store' THEN 'store ' || message ELSE stage END AS step, at FROM job_events
        WHERE job_id = JOB AND attempt = (SELECT max(attempt) FROM job_events WHERE job_id = JOB)) e
  GROUP BY step) s"
echo "takeover:    $(q "${stages//JOB/$job}")"
echo "undisturbed: $(q "${stages//JOB/$again}")"
echo "stored points of job $again: $(q "SELECT round(sum(pg_column_size(points)) / 1e6, 1) || ' MB for ' || round(sum(point_count) * 12 / 1e6, 1) || ' MB of float32' FROM submaps WHERE job_id = $again")"
echo "stored corrected GSF of job $again: $(q "SELECT round(sum(pg_column_size(data)) / 1e6, 1) || ' MB for ' || round(sum(length(data)) / 1e6, 1) || ' MB' FROM job_file_chunks WHERE job_id = $again AND name LIKE '%.gsf'")"
resumed=$(seconds "$job")
whole=$(seconds "$again")
poses="SELECT md5(string_agg(pose::text, ';' ORDER BY submap)) FROM optimized_poses WHERE job_id ="
same=$([ "$(q "$poses $job")" = "$(q "$poses $again")" ] && echo identical || echo DIFFERENT)
awk -v f="$fraction" -v r="$resumed" -v k="$killed" -v e="$finished" -v l="$lease" -v w="$whole" -v s="$same" 'BEGIN {
  printf "killed at register %s: the takeover attempt %.1f s (finished %.1f s after the kill, lease %d s), undisturbed %.1f s, ratio %.2f; poses %s\n", f, r, e - k, l, w, r / w, s }'
[ "$same" = identical ]
