#!/usr/bin/env bash
# Builds the GSF reader's libFuzzer target with Debian's clang (ASan + UBSan) and runs it for a
# bounded time with the real GSF files as seed corpus. Exit 0: no crash, leak or sanitizer report.
#   scripts/fuzz-gsf.sh BUILD_DIR GSF_DATA_DIR [SECONDS]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=$1
data=$2
seconds=${3:-60}
out="$build/fuzz"
mkdir -p "$out/corpus"
cp "$data"/*.gsf "$out/corpus/"
clang++ -std=c++20 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
  -I"$root" "$root/tests/fuzz/gsf_reader_fuzz.cpp" "$root/core/io/gsf/gsf_reader.cpp" \
  "$root/core/io/byte_source.cpp" -o "$out/gsf_reader_fuzz"
# 64 KiB inputs: the start of EX1811 (header, processing parameters, attitude) and all of the
# gsfpy file (pings); new inputs go to a scratch corpus, the seeds stay as they are.
mkdir -p "$out/new"
"$out/gsf_reader_fuzz" -max_total_time="$seconds" -max_len=65536 -timeout=10 -rss_limit_mb=2048 \
  -print_final_stats=1 "$out/new" "$out/corpus"
