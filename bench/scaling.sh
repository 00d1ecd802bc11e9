#!/usr/bin/env bash
# Issue 35's scaling curve: for each scenario, the simulation and an `mchs` run of it, with wall
# time, CPU time and peak RSS (GNU time) and each stage's time (report.json), one markdown row each.
#   bench/scaling.sh [--scenarios "small lake large xlarge"] [--work DIR] [--keep]
# A bundle and its products are deleted after its run unless --keep (xlarge's pings.csv is about
# 22 GB).
set -euo pipefail
cd "$(dirname "$0")/.."
scenarios="small lake large xlarge" work=/tmp/bathyslam-scaling keep=0
while [[ $# -gt 0 ]]; do
  case "$1" in
    --scenarios) scenarios=$2; shift 2 ;;
    --work) work=$2; shift 2 ;;
    --keep) keep=1; shift ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
bathyslam=${BATHYSLAM:-build/client/bathyslam}
mkdir -p "$work"
# GNU time's wall seconds, CPU seconds and peak RSS (MiB) of a command, as "wall cpu rss".
measured() {
  local log=$1; shift
  if ! /usr/bin/time -f "%e %U %S %M" -o "$log.time" "$@" > "$log" 2>&1; then
    echo "failed: $*; see $log" >&2
    return 1
  fi
  awk '{printf "%.1f %.1f %.0f", $1, $2 + $3, $4 / 1024}' "$log.time"
}
echo "| scenario | soundings | step | wall (s) | CPU (s) | peak RSS (MiB) | submaps / features / register / graph / eval (s) |"
echo "|---|---|---|---|---|---|---|"
for scenario in $scenarios; do
  bundle=$work/$scenario
  figures=$(measured "$work/$scenario-simulate.log" "$bathyslam" simulate --scenario "$scenario" --seed 1 --out "$bundle")
  read -r wall cpu rss <<< "$figures"
  soundings=$(awk '/soundings/ {print $3; exit}' "$work/$scenario-simulate.log")
  echo "| $scenario | $soundings | simulate | $wall | $cpu | $rss | |"
  figures=$(measured "$work/$scenario-mchs.log" "$bathyslam" process "$bundle" --config mchs --out "$bundle-mchs")
  read -r wall cpu rss <<< "$figures"
  stages=$(python3 -c "import json, sys; t = json.load(open(sys.argv[1]))['timings_s']; print(' / '.join(f\"{t.get(k, 0):.1f}\" for k in ('submaps', 'features', 'register', 'graph', 'eval')))" "$bundle-mchs/report.json")
  echo "| $scenario | $soundings | process --config mchs | $wall | $cpu | $rss | $stages |"
  [[ $keep == 1 ]] || rm -rf "$bundle" "$bundle-mchs"
done
