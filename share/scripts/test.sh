#!/usr/bin/env bash
# The test command of the README: installs what is missing, builds (Release), runs every test.
# Tests that need ../shared/data skip with a message when it is absent.
# The golden outputs (label "golden", share/scripts/golden.sh) run with the other tests. Then:
#  - mutation.sh: known-bad changes (tests/mutation/*.patch) built in a scratch copy; each must be
#    caught by its tests (doc/reliability.md, "The test suite's own check").
# Then the reliability stages (issue 8, doc/reliability.md), each in its own build folder:
#  - sanitize.sh: ASan + UBSan build of the unit tests and the app, unit tests and end-to-end runs;
#  - fuzz.sh: libFuzzer (clang) on the calib, dataset-folder, ini and rawlog parsers, a bounded time
#    per target (IMMSLAM_FUZZ_SECONDS, default 30 in CI).
# IMMSLAM_CI_MUTATION=0, IMMSLAM_CI_SANITIZE=0 or IMMSLAM_CI_FUZZ=0 skip a stage (e.g. for a quick
# local run). ccache, when installed (install-deps.sh installs it), speeds up the rebuilds.
set -euo pipefail
cd "$(dirname "$0")/../.."
share/scripts/install-deps.sh
launcher=()
if command -v ccache > /dev/null; then
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  export CCACHE_BASEDIR="$(pwd)"
fi
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release "${launcher[@]}"
cmake --build build -j"$(nproc)"
ctest --test-dir build --output-on-failure -j"$(nproc)" --timeout 1200
if [ "${IMMSLAM_CI_MUTATION:-1}" != 0 ]; then
  share/scripts/mutation.sh
fi
if [ "${IMMSLAM_CI_SANITIZE:-1}" != 0 ]; then
  share/scripts/sanitize.sh build-asan
fi
if [ "${IMMSLAM_CI_FUZZ:-1}" != 0 ]; then
  FUZZ_BUILD_DIR=build-fuzz share/scripts/fuzz.sh "${IMMSLAM_FUZZ_SECONDS:-30}"
fi
