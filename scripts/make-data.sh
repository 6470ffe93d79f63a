#!/usr/bin/env bash
# Regenerates the small meshes in data/ with lodkit itself (no third-party files).
set -euo pipefail
cd "$(dirname "$0")/.."
lodkit=build/cli/lodkit
[ -x "$lodkit" ] || scripts/build.sh
$lodkit -q generate torus -o data/torus.ply --tolerance 0.005
$lodkit -q generate sphere -o data/sphere_uv.obj --tolerance 0.01 --uvs --normals
$lodkit -q generate box -o data/box.off --size 2 1 0.5 --divisions 4
$lodkit -q generate pyramid -o data/pyramid.ply
$lodkit -q generate grid -o data/grid.ply --size 2 --divisions 16 --uvs
$lodkit -q terrain -o data/terrain.ply --levels 6 --colour --seed 1
