#!/usr/bin/env bash
# Builds the libFuzzer targets with Debian's clang (libclang-rt-14-dev) and runs each for
# FUZZ_SECONDS (default 60) from the seed corpus in fuzz/corpus/, into build-fuzz/.
set -euo pipefail
cd "$(dirname "$0")/.."
out=build-fuzz
mkdir -p "$out/corpus"
sources=(core/io/bundle_reader.cpp core/io/csv.cpp core/io/byte_source.cpp core/io/bounded_json.cpp core/io/problem.cpp
         core/io/crs.cpp core/io/bundle_files.cpp)
clang++ -std=c++20 -O1 -g -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined -I. -I/usr/include/gdal \
  fuzz/bundle_fuzzer.cpp "${sources[@]}" -lproj -lgdal -o "$out/bundle_fuzzer"
cp -n fuzz/corpus/* "$out/corpus/" 2> /dev/null || true
"$out/bundle_fuzzer" -max_total_time="${FUZZ_SECONDS:-60}" -max_len=4096 -timeout=10 -rss_limit_mb=2048 \
  "$out/corpus" 2>&1 | tail -n 5
