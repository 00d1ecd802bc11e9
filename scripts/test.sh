#!/usr/bin/env bash
# The README's test command: installs dependencies, builds, and runs every test with ctest (the
# fuzzers among them, a minute each); then the unit and storage tests again under
# AddressSanitizer and UndefinedBehaviorSanitizer.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
(cd build && ctest --output-on-failure --timeout 900 -j"$(nproc)")
bash scripts/sanitize.sh
