#!/usr/bin/env bash
# Simplification benchmark against meshoptimizer, OpenMesh's Decimater and CGAL (docs/benchmarks.md):
# every method over the sweep 50 % .. 0.5 % of the faces, a Markdown table on stdout, a CSV and three
# charts (error vs faces, error vs time, validity vs reduction; PNG and SVG); for the default set also
# the stability suite through every method (stability.csv, stability.md).
#
#   scripts/bench-simplify.sh                  # the default set from ../shared/models -> docs/benchmarks/simplify*
#   scripts/bench-simplify.sh my_scan.ply ...  # your meshes -> bench-results/simplify* (OUT=dir to change)
#
# TARGETS=0.1,0.01 narrows the sweep; METHODS=quadric,meshopt,... picks methods.
set -euo pipefail
cd "$(dirname "$0")/.."
meshes=()
for m in "$@"; do meshes+=("$(realpath "$m")"); done
scripts/build.sh -DLODKIT_BUILD_BENCH=ON >/dev/null
m=../shared/models
if [ ${#meshes[@]} -eq 0 ]; then
  meshes=("$m/scans/stanford_bunny_zipper.ply" "$m/scans/horse.ply" "$m/cad/fandisk.obj" "$m/cad/rocker_arm.obj"
          "$m/attributes/spot_uv.obj" "$m/large/igea_loop1.ply")
  out=${OUT:-docs/benchmarks}
else
  out=${OUT:-bench-results}   # never overwrite the published numbers with a user's run
fi
mkdir -p "$out"
methods=()
[ -n "${METHODS:-}" ] && methods=(--methods "$METHODS")
build/bench/lodkit_bench_simplify --targets "${TARGETS:-0.5,0.2,0.1,0.05,0.02,0.01,0.005}" "${methods[@]}" \
  --csv "$out/simplify.csv" "${meshes[@]}"
/usr/bin/python3 bench/plot_simplify.py "$out/simplify.csv" "$out/simplify"
if [ $# -eq 0 ]; then
  # The stability suite (meshes built to make simplifiers fail) through every method.
  build/bench/lodkit_bench_stability --csv "$out/stability.csv" 2>/dev/null > "$out/stability.md"
  echo "wrote $out/stability.csv and $out/stability.md" >&2
fi
echo "wrote $out/simplify.csv and $out/simplify_{error_vs_faces,error_vs_time,validity_vs_reduction}.{png,svg}" >&2
