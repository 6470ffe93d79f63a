#!/usr/bin/env bash
# The whole test suite under AddressSanitizer and UndefinedBehaviorSanitizer (g++). A read past an
# array or an overflowing cast that a release build happens to answer right becomes a failure here.
# Not part of CI: on 2 cores the instrumented build takes about 25 minutes and its run 16. Run it by hand
# after touching the hand-written kernels (the closest-point tree, the scorers, the queues, the
# readers). See docs/fuzzing.md, "The test suite under sanitizers".
#
#   scripts/sanitize.sh                   # every test (the CLI tests run the instrumented lodkit too)
#   scripts/sanitize.sh 'AabbTree|Cli'    # the tests whose names match a CTest regular expression
#
# Builds into build-sanitize/ (RelWithDebInfo, so reports name lines) and exits non-zero on any report.
set -euo pipefail
cd "$(dirname "$0")/.."
generator=()
command -v ninja >/dev/null 2>&1 && generator=(-G Ninja)
# (g++ leaves float-to-integer overflow out of "undefined": asked for by name.)
flags="-fsanitize=address,undefined,float-cast-overflow -fno-sanitize-recover=undefined,float-cast-overflow -fno-omit-frame-pointer"
if [ ! -f build-sanitize/CMakeCache.txt ]; then
  # (CMake links with the compile flags too, so the sanitizers' runtimes come in without linker flags.)
  cmake -S . -B build-sanitize "${generator[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DLODKIT_BUILD_BENCH=OFF -DLODKIT_TEST_TIMEOUT=3600 \
    -DCMAKE_CXX_FLAGS="$flags"
fi
cmake --build build-sanitize --parallel "$(nproc)"

# Leaks count too; a report ends the process with a failure, which CTest shows with its stack.
export ASAN_OPTIONS=detect_leaks=1:strict_string_checks=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
filter=()
[ $# -gt 0 ] && filter=(-R "$1")
# (Not the install check: a consumer built without the sanitizers cannot link the instrumented library.)
ctest --test-dir build-sanitize --output-on-failure --parallel "$(nproc)" -E '^Install[.]' "${filter[@]}"
