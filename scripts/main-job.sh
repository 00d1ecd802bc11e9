#!/usr/bin/env bash
# The README's main-job command. For now: build, simulate the `small` survey, summarise it and
# process it offline with the `gicp` configuration. Later issues make it the full service round
# trip (private PostgreSQL, server, upload, job, tiles).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
out=${BATHYSLAM_DEMO_DIR:-demo}
mkdir -p "$out"
./build/client/bathyslam simulate --scenario small --seed 1 --drift paper --out "$out/small"
./build/client/bathyslam inspect "$out/small"
./build/client/bathyslam inspect --json "$out/small" > "$out/small-summary.json"
./build/client/bathyslam process "$out/small" --config gicp --out "$out/small-gicp"
echo
echo "bundle:  $out/small"
echo "summary: $out/small-summary.json"
echo "slam:    $out/small-gicp (trajectory.csv, report.json, plots)"
