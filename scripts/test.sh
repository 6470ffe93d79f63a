#!/usr/bin/env bash
# The whole test suite: builds lodkit, then runs every test (unit, CLI end to end, bad-input corpus,
# install-and-consume check) through CTest. Benchmarks are built but never run here.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh -DLODKIT_BUILD_TESTS=ON
ctest --test-dir build --output-on-failure --parallel "$(nproc)"
