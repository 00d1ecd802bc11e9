#!/usr/bin/env bash
# Builds the survey bundle parsers' libFuzzer target (nav.csv, pings.csv, survey.json) with
# Debian's clang (ASan + UBSan) and runs it for a bounded time from the seed corpus in
# tests/fuzz/bundle_corpus. Exit 0: no crash, leak or sanitizer report.
#   scripts/fuzz-bundle.sh BUILD_DIR [SECONDS]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=$1/fuzz-bundle
seconds=${2:-60}
mkdir -p "$out/corpus" "$out/new"
sources=(core/io/bundle_reader.cpp core/io/csv.cpp core/io/byte_source.cpp core/io/bounded_json.cpp core/io/problem.cpp
         core/io/crs.cpp core/io/bundle_files.cpp core/io/tar_members.cpp)
clang++ -std=c++20 -O1 -g -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined -I"$root" -I/usr/include/gdal \
  "$root/tests/fuzz/bundle_reader_fuzz.cpp" "${sources[@]/#/$root/}" -lproj -lgdal -o "$out/bundle_reader_fuzz"
cp -rn "$root"/tests/fuzz/bundle_corpus/* "$out/corpus/"
# New inputs go to a scratch corpus; the seeds stay as they are.
"$out/bundle_reader_fuzz" -max_total_time="$seconds" -max_len=4096 -timeout=10 -rss_limit_mb=2048 \
  -print_final_stats=1 "$out/new" "$out/corpus"
