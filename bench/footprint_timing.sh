#!/usr/bin/env bash
# Issue 38: the time per sounding of every stage at each altitude and on the real deep-water EX1811
# file, from one `mchs` run each (seed 1; `lake` at 9, 30 and 80 m, `small` at 1500 m).
#   bench/footprint_timing.sh [--work DIR]
# One markdown row per survey: soundings, the footprint's scale, each stage's microseconds per
# sounding, the wall time and peak memory of `process`.
set -euo pipefail
cd "$(dirname "$0")/.."
work=/tmp/bathyslam-footprint
[[ ${1:-} == --work ]] && work=$2
bathyslam=${BATHYSLAM:-build/client/bathyslam}
ex1811=${EX1811:-../shared/data/gsf/EX1811_EM302_0059_20181102_212138.gsf}
mkdir -p "$work"
row() {  # name, then the process arguments
  local name=$1; shift
  /usr/bin/time -f "%e %M" -o "$work/$name.time" "$bathyslam" process "$@" --config mchs --out "$work/$name-mchs" > /dev/null 2>&1
  /usr/bin/python3 - "$name" "$work/$name-mchs/report.json" "$work/$name.time" <<'PY'
import json, sys
name, report, timing = sys.argv[1:]
r = json.load(open(report))
n = r["submaps"]["soundings"]
wall, rss_kb = open(timing).read().split()
stages = ["submaps", "features", "register", "graph", "eval"]
us = " | ".join(f"{1e6 * r['timings_s'].get(s, 0) / n:.3f}" for s in stages)
print(f"| {name} | {n} | {r['footprint']['spacing_m']:.3g} | x{r['footprint']['scale']:g} | {us} | {wall} | {int(rss_kb) / 1024:.0f} |")
PY
}
echo "| survey | soundings | spacing (m) | lengths | submaps (µs/sounding) | features | register | graph | eval | wall (s) | peak RSS (MiB) |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for spec in "lake 9" "lake 30" "lake 80" "small 1500"; do
  set -- $spec
  altitude=(); [[ $2 != 9 ]] && altitude=(--altitude "$2")
  bundle=$work/$1-altitude$2
  [[ -f $bundle/survey.json ]] || "$bathyslam" simulate --scenario "$1" --seed 1 "${altitude[@]}" --out "$bundle" > /dev/null
  row "$1-altitude$2" "$bundle"
  rm -rf "$bundle"
done
row EX1811 "$ex1811"
