#!/usr/bin/env bash
# Load-time benchmark against OpenMesh and tinyobjloader (docs/benchmarks.md). Default mesh: the
# shared 1.07M-triangle igea_loop1.ply if present, else a generated 1.3M-triangle icosphere.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh -DLODKIT_BUILD_BENCH=ON >/dev/null
mesh=${1:-../shared/models/large/igea_loop1.ply}
[ -f "$mesh" ] || mesh=""
build/bench/lodkit_bench_io $mesh --runs "${RUNS:-5}"
