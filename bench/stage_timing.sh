#!/usr/bin/env bash
# Per-stage wall time of one `bathyslam process` job, from its report.json.
#   bench/stage_timing.sh BUNDLE [CONFIG=mchs] [THREADS=0]
# e.g. build/client/bathyslam simulate --scenario lake --seed 1 --out /tmp/lake1
#      bench/stage_timing.sh /tmp/lake1 mchs
set -euo pipefail
cd "$(dirname "$0")/.."
bundle=$1 config=${2:-mchs} threads=${3:-0}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
start=$(date +%s.%N)
"${BATHYSLAM:-build/client/bathyslam}" process "$bundle" --config "$config" --threads "$threads" --out "$out" >/dev/null 2>&1
end=$(date +%s.%N)
python3 - "$out/report.json" "$start" "$end" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
total = float(sys.argv[3]) - float(sys.argv[2])
print("| stage | seconds | share |")
print("|---|---|---|")
for stage, seconds in r["timings_s"].items():
    print(f"| {stage} | {seconds:.2f} | {100 * seconds / total:.0f} % |")
pipeline = sum(r["timings_s"].values())
print(f"| map files, report, plots (outside the pipeline) | {total - pipeline:.2f} | {100 * (total - pipeline) / total:.0f} % |")
print(f"| **total (process wall time)** | {total:.2f} | |")
PY
