#!/usr/bin/env bash
# The README's test command: installs dependencies, builds, and runs every test with ctest; then
# the unit and storage tests again under AddressSanitizer and UndefinedBehaviorSanitizer, and
# the bundle reader's fuzzer for a minute.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
(cd build && ctest --output-on-failure --timeout 900 -j"$(nproc)")
bash scripts/sanitize.sh
FUZZ_SECONDS=60 bash fuzz/run.sh
