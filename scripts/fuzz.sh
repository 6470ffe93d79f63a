#!/usr/bin/env bash
# Fuzzes lodkit's readers and CSG trees (and, with --deep, every method on what they read) with libFuzzer under
# AddressSanitizer and UndefinedBehaviorSanitizer. Not part of the test suite: run it by hand.
#
#   scripts/fuzz.sh                  # every target, 60 s each
#   scripts/fuzz.sh 600 ply pm       # these targets, 10 minutes each
#   scripts/fuzz.sh --deep 300 obj   # also simplify, decimate, build a .pm and compare what reads
#
# Needs clang (Debian 12: apt-get install clang). Builds into build-fuzz/, seeds each target's
# corpus with small meshes the CLI generates (build-fuzz/corpus/<target>, kept between runs, so later
# runs start where earlier ones stopped; deep runs keep build-fuzz/corpus-deep/<target>), and writes any finding to build-fuzz/findings/. Exits 1 if
# there is one; reproduce it with build-fuzz/tests/fuzz/fuzz_<target> <file>. See docs/fuzzing.md.
set -euo pipefail
cd "$(dirname "$0")/.."

deep=0
if [ "${1:-}" = "--deep" ]; then deep=1; shift; fi
seconds=${1:-60}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(ply obj off stl drc pm csg)

command -v clang++ >/dev/null || { echo "fuzz.sh: needs clang++ (apt-get install clang)" >&2; exit 2; }
generator=()
command -v ninja >/dev/null 2>&1 && generator=(-G Ninja)
if [ ! -f build-fuzz/CMakeCache.txt ]; then
  CC=clang CXX=clang++ cmake -S . -B build-fuzz "${generator[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DLODKIT_FUZZ=ON -DLODKIT_BUILD_TESTS=OFF -DLODKIT_BUILD_BENCH=OFF
fi
cmake --build build-fuzz --parallel "$(nproc)"

export ASAN_OPTIONS=detect_leaks=0 UBSAN_OPTIONS=print_stacktrace=1
lodkit=build-fuzz/cli/lodkit
corpus=build-fuzz/corpus
seeds=build-fuzz/seeds
mkdir -p "$corpus" "$seeds" build-fuzz/findings
if [ ! -f "$seeds/done" ]; then
  # Small shapes with every kind of attribute, then each in every encoding the readers know.
  $lodkit -q generate sphere -o "$seeds/sphere.ply" --segments 8 --rings 6 --uvs --normals
  $lodkit -q generate torus -o "$seeds/torus.ply" --major-segments 8 --minor-segments 5
  $lodkit -q generate grid -o "$seeds/grid.ply" --divisions 4 --uvs
  $lodkit -q generate box -o "$seeds/box.ply" --divisions 2
  $lodkit -q generate cone -o "$seeds/cone.ply" --segments 6 --normals
  $lodkit -q terrain -o "$seeds/terrain.ply" --levels 2 --colour
  for target in ply obj off stl drc pm; do mkdir -p "$corpus/$target"; done
  for mesh in "$seeds"/*.ply; do
    name=$(basename "$mesh" .ply)
    $lodkit -q convert "$mesh" "$corpus/ply/$name.ply"
    $lodkit -q convert "$mesh" "$corpus/ply/${name}_ascii.ply" --ascii
    $lodkit -q convert "$mesh" "$corpus/ply/${name}_be.ply" --big-endian
    $lodkit -q convert "$mesh" "$corpus/obj/$name.obj"
    $lodkit -q convert "$mesh" "$corpus/off/$name.off"
    $lodkit -q convert "$mesh" "$corpus/stl/$name.stl"
    $lodkit -q convert "$mesh" "$corpus/stl/${name}_ascii.stl" --ascii
    $lodkit -q convert "$mesh" "$corpus/drc/$name.drc"
    $lodkit -q convert "$mesh" "$corpus/drc/${name}_float.drc" --quantize 0
    $lodkit -q pm build "$mesh" -o "$corpus/pm/$name.pm"
    $lodkit -q pm build "$mesh" -o "$corpus/pm/${name}_q.pm" --quantize 12
    $lodkit -q pm build "$mesh" -o "$corpus/pm/${name}_draco.pm" --quantize 12 --draco
    $lodkit -q pm build "$mesh" -o "$corpus/pm/${name}_blocks.pm" --quantize 10 --block 4 --keep-order
  done
  $lodkit -q pm build "$seeds/sphere.ply" -o "$corpus/pm/sphere_hoppe.pm" --method hoppe --measure
  touch "$seeds/done"
fi
if [ ! -d "$corpus/csg" ]; then  # the bundled trees and one of each primitive
  mkdir -p "$corpus/csg"
  cp data/csg/*.json "$corpus/csg/"
  echo '{"op": "union", "children": [{"primitive": "sphere", "radius": 0.6},
    {"primitive": "torus", "major_radius": 1, "minor_radius": 0.2, "transform": {"scale": [1, 1, 2]}}]}' \
    > "$corpus/csg/sphere_torus.json"
  echo '{"op": "intersection", "children": [{"primitive": "cone", "radius": 1, "height": 2},
    {"primitive": "cylinder", "radius": 0.5, "height": 3, "transform": {"rotate": {"euler": [90, 0, 0]}}}]}' \
    > "$corpus/csg/cone_cylinder.json"
fi

found=0
for target in "${targets[@]}"; do
  echo "fuzz.sh: $target for $seconds s$([ $deep = 1 ] && [ "$target" != pm ] && echo ', deep')"
  env_deep=() timeout=30 target_corpus="$corpus/$target"
  # Deep runs simplify, build a progressive mesh and certify distances per input: under the
  # sanitizers a few take tens of seconds (a third of a second without them). They keep a corpus of
  # their own, seeded with the generated files alone: run once through the readers' corpus (hundreds
  # of files grown by coverage of the parsers), they spent half an hour before mutating anything.
  if [ $deep = 1 ]; then
    env_deep=(LODKIT_FUZZ_DEEP=1) timeout=120 target_corpus="build-fuzz/corpus-deep/$target"
    if [ ! -d "$target_corpus" ]; then
      mkdir -p "$target_corpus"
      find "$corpus/$target" -maxdepth 1 -type f -regextype posix-extended ! -regex '.*/[0-9a-f]{40}' -exec cp {} "$target_corpus/" \;
    fi
  fi
  if ! env "${env_deep[@]}" "build-fuzz/tests/fuzz/fuzz_$target" "$target_corpus" -max_total_time="$seconds" \
      -max_len=8192 -timeout="$timeout" -rss_limit_mb=4096 -print_final_stats=1 \
      -artifact_prefix="build-fuzz/findings/$target-" > "build-fuzz/$target.log" 2>&1; then
    found=1
    echo "fuzz.sh: $target: a finding, see build-fuzz/$target.log and build-fuzz/findings/" >&2
  fi
  grep -E "^stat::number_of_executed_units" "build-fuzz/$target.log" || true
done
exit $found
