#!/usr/bin/env bash
# Issue 16: two servers on one database; the one running an `mchs` job is killed outright
# (SIGKILL); the other must finish the job, after the lease expires, with the poses of an
# undisturbed run. Runs service_reliability's KilledServerTest N times (default 10) and prints
# each run's verdict and how long after the kill the job was finished.
#   bench/kill_server_repeat.sh [N] [BUILD_DIR]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
runs=${1:-10}
build=$(cd "${2:-$root/build}" && pwd)
work=$(mktemp -d)
trap 'bash "$root/scripts/pg.sh" destroy "$work/pg" > /dev/null 2>&1; rm -rf "$work"' EXIT
bash "$root/scripts/pg.sh" start "$work/pg" > /dev/null
"$build/client/bathyslam" simulate --scenario small --seed 1 --out "$work/small" > /dev/null
passed=0
for run in $(seq 1 "$runs"); do
  if out=$(env BATHYSLAM="$build/client/bathyslam" BATHYSLAM_SERVER_BIN="$build/server/bathyslam-server" \
             BATHYSLAM_TEST_PG="$work/pg" PG_SH="$root/scripts/pg.sh" SMALL_BUNDLE="$work/small" \
             PROTO_DIR="$root/proto" GSF_DATA="$root/tests/data/gsf" BATHYSLAM_PYTHONPATH="$build/python" \
             /usr/bin/python3 "$root/tests/python/reliability_test.py" KilledServerTest 2>&1); then
    passed=$((passed + 1))
    echo "run $run: pass, $(grep -o "finished by the other [0-9.]* s after the kill.*" <<< "$out")"
  else
    echo "run $run: FAIL"
    echo "$out" | tail -n 20
  fi
done
echo "$passed of $runs runs: the other server finished the killed one's job with identical poses"
[ "$passed" -eq "$runs" ]
