#!/usr/bin/env bash
# Simplification benchmark against meshoptimizer, OpenMesh's Decimater and CGAL (docs/benchmarks.md).
# Arguments: meshes (default: a set from ../shared/models). Writes docs/benchmarks/simplify.csv.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh -DLODKIT_BUILD_BENCH=ON >/dev/null
m=../shared/models
meshes=("$@")
if [ ${#meshes[@]} -eq 0 ]; then
  meshes=("$m/scans/stanford_bunny_zipper.ply" "$m/scans/horse.ply" "$m/cad/fandisk.obj" "$m/cad/rocker_arm.obj"
          "$m/attributes/spot_uv.obj" "$m/large/igea_loop1.ply")
fi
mkdir -p docs/benchmarks
build/bench/lodkit_bench_simplify --csv docs/benchmarks/simplify.csv "${meshes[@]}"
