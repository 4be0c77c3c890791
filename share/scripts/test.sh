#!/usr/bin/env bash
# The test command of the README: installs what is missing, builds (Release), runs every test.
# Tests that need ../shared/data skip with a message when it is absent.
# Then the reliability stages (issue 8, doc/reliability.md), each in its own build folder:
#  - sanitize.sh: ASan + UBSan build of the unit tests and the app, unit tests and end-to-end runs;
#  - fuzz.sh: libFuzzer (clang) on the calib, dataset-folder, ini and rawlog parsers, a bounded time
#    per target (IMMSLAM_FUZZ_SECONDS, default 30 in CI).
# IMMSLAM_CI_SANITIZE=0 or IMMSLAM_CI_FUZZ=0 skip a stage (e.g. for a quick local run).
set -euo pipefail
cd "$(dirname "$0")/../.."
share/scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
ctest --test-dir build --output-on-failure -j"$(nproc)" --timeout 1200
if [ "${IMMSLAM_CI_SANITIZE:-1}" != 0 ]; then
  share/scripts/sanitize.sh build-asan
fi
if [ "${IMMSLAM_CI_FUZZ:-1}" != 0 ]; then
  FUZZ_BUILD_DIR=build-fuzz share/scripts/fuzz.sh "${IMMSLAM_FUZZ_SECONDS:-30}"
fi
