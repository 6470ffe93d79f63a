#!/usr/bin/env bash
# Simplification benchmark against meshoptimizer, OpenMesh's Decimater and CGAL (docs/benchmarks.md).
# Arguments: meshes (default: a set from ../shared/models). Writes docs/benchmarks/simplify.csv and the
# charts docs/benchmarks/simplify_*.{png,svg}. TARGETS=0.1,0.01 narrows the sweep.
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
# The sweep of the speed-vs-accuracy issue: 50 % down to 0.5 % of the faces.
build/bench/lodkit_bench_simplify --targets "${TARGETS:-0.5,0.2,0.1,0.05,0.02,0.01,0.005}" \
  --csv docs/benchmarks/simplify.csv "${meshes[@]}"
/usr/bin/python3 bench/plot_simplify.py docs/benchmarks/simplify.csv docs/benchmarks/simplify
