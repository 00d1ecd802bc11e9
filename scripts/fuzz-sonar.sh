#!/usr/bin/env bash
# Builds one sonar-format reader's libFuzzer target with Debian's clang (ASan + UBSan) and runs it
# for a bounded time with the real files of that format as seed corpus. Exit 0: no crash, leak,
# hang or sanitizer report.
#   scripts/fuzz-sonar.sh gsf|all|xtf BUILD_DIR DATA_DIR [SECONDS]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
format=$1
build=$2
data=$3
seconds=${4:-60}
case "$format" in
  # 64 KiB: the start of EX1811 (header, processing parameters, attitude) and all of the gsfpy file.
  gsf) sources=(core/io/gsf/gsf_reader.cpp) max_len=65536 ;;
  # 384 KiB: both seed files whole.
  all) sources=(core/io/kongsberg/all_reader.cpp) max_len=393216 ;;
  # 64 KiB: the file header and the first twenty-odd pings with their navigation.
  xtf) sources=(core/io/xtf/xtf_reader.cpp) max_len=65536 ;;
  *) echo "unknown format $format (gsf, all or xtf)" >&2; exit 2 ;;
esac
out="$build/fuzz-$format"
mkdir -p "$out/corpus" "$out/new"
cp "$data"/*."$format" "$out/corpus/"
clang++ -std=c++20 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
  -I"$root" "$root/tests/fuzz/${format}_reader_fuzz.cpp" "${sources[@]/#/$root/}" \
  "$root/core/io/byte_source.cpp" -o "$out/${format}_reader_fuzz"
# New inputs go to a scratch corpus; the seeds stay as they are.
"$out/${format}_reader_fuzz" -max_total_time="$seconds" -max_len="$max_len" -timeout=10 -rss_limit_mb=2048 \
  -print_final_stats=1 "$out/new" "$out/corpus"
