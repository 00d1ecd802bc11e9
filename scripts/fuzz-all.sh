#!/usr/bin/env bash
# Builds the Kongsberg .all reader's libFuzzer target with Debian's clang (ASan + UBSan) and runs
# it for a bounded time with the real .all files as seed corpus. Exit 0: no crash, leak or
# sanitizer report.
#   scripts/fuzz-all.sh BUILD_DIR ALL_DATA_DIR [SECONDS]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=$1
data=$2
seconds=${3:-60}
out="$build/fuzz-all"
mkdir -p "$out/corpus" "$out/new"
cp "$data"/*.all "$out/corpus/"
clang++ -std=c++20 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
  -I"$root" "$root/tests/fuzz/all_reader_fuzz.cpp" "$root/core/io/kongsberg/all_reader.cpp" \
  "$root/core/io/byte_source.cpp" -o "$out/all_reader_fuzz"
# 384 KiB inputs: both seed files whole.
"$out/all_reader_fuzz" -max_total_time="$seconds" -max_len=393216 -timeout=10 -rss_limit_mb=2048 \
  -print_final_stats=1 "$out/new" "$out/corpus"
