#!/usr/bin/env bash
# AddressSanitizer + UndefinedBehaviorSanitizer check (issue 8): builds the unit tests and
# imm-monoslam with -DIMMSLAM_SANITIZE=ON (-O1, line tables) in their own build folder, runs every
# unit test (ctest label "unit"), the fuzz targets on their seeds and former crashes (label "fuzz"),
# one short end-to-end run of each shipped config on the built-in rendered scene and runs on a
# damaged dataset folder and rawlog. Any sanitizer report fails the script (zero reports required).
#
# Usage: share/scripts/sanitize.sh [BUILD_DIR]     (default build-asan)
# Environment: JOBS (parallel jobs, default nproc), CXX (compiler; default the system's),
#   SANITIZE_TESTS (ctest -R regex restricting the unit tests, default all), SANITIZE_EXCLUDE (ctest
#   -E regex of tests skipped, default the one too slow for its TIMEOUT under ASan),
#   SANITIZE_FRAMES (frames of the end-to-end runs, default 60).
set -euo pipefail
cd "$(dirname "$0")/../.."
ROOT=$(pwd)
BUILD=${1:-build-asan}
JOBS=${JOBS:-$(nproc)}
FRAMES=${SANITIZE_FRAMES:-60}
T0=$(date +%s)

# LeakSanitizer: leaks inside libraries we do not own are suppressed, by library or MRPT class:
# Mesa/EGL and fontconfig (offscreen snapshots), libgphoto2/libusb (OpenCV's VideoCapture probing
# cameras), libav* (MRPT's CFFMPEG_InputStream::openURL never frees its codec context and options;
# the fast unwinder stops inside libavutil, so the suppression names the library). Leaks allocated
# by our code are not suppressed.
SUPP="$ROOT/$BUILD/sanitizer-suppressions"
mkdir -p "$ROOT/$BUILD"
cat > "$SUPP.lsan" <<'EOF'
leak:libEGL
leak:libEGL_mesa
leak:libGLX
leak:libGL.so
leak:libgallium
leak:dri.so
leak:libglapi
leak:libfontconfig
leak:libdbus
leak:libgphoto2
leak:libgphoto2_port
leak:libusb
leak:libavutil
leak:libavcodec
leak:libavformat
EOF
# OpenCV's VideoCapture(index) probes libgphoto2 cameras, whose USB plugin leaks and is unloaded
# (its frames cannot be named in a suppression): that backend is not needed here.
export OPENCV_VIDEOIO_PRIORITY_GPHOTO2=0
# Mesa's llvmpipe (the offscreen scene snapshots) keeps its rendering threads alive until the process
# exits; LeakSanitizer's stop-the-world tracer then has to suspend them and can crash doing so
# ("Tracer caught signal 11 ... LeakSanitizer has encountered a fatal error", google/sanitizers#1353).
# LP_NUM_THREADS=0 makes llvmpipe draw in the calling thread: a run ends with its main thread alone.
export LP_NUM_THREADS=0
export ASAN_OPTIONS="detect_leaks=1:halt_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1:print_summary=1"
export LSAN_OPTIONS="suppressions=$SUPP.lsan:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:print_summary=1"

# (UBSan's alignment check is off for libs/viz only: see libs/viz/CMakeLists.txt.)

echo "== sanitize: configure $BUILD (ASan + UBSan, -O1)"
cmake -S . -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" -DIMMSLAM_SANITIZE=ON \
  -DIMMSLAM_BUILD_BENCHMARKS=OFF -DIMMSLAM_BUILD_TESTS=ON \
  > "$BUILD/configure.log"

# The unit-test binaries (libs/<mod>/tests), the fuzz targets on their seeds and former crashes
# (fuzz_regression_unittest) and the programs: not the system and robustness tests (long runs of
# the whole estimator, run by the normal build).
mapfile -t UNIT < <(cmake --build "$BUILD" --target help | sed -n 's/^\.\.\. \([a-z_]*_unittest\)$/\1/p' |
                    grep -v -E '^(system|robustness_.*)_unittest$' | sort)
echo "== sanitize: building imm-monoslam, imm-render, dataset2rawlog and ${#UNIT[@]} unit-test binaries: ${UNIT[*]}"
cmake --build "$BUILD" -j"$JOBS" --target imm-monoslam imm-render dataset2rawlog "${UNIT[@]}"

echo "== sanitize: unit tests and fuzz regressions"
CTEST_ARGS=(--test-dir "$BUILD" -L "^(unit|fuzz)$" --output-on-failure -j"$JOBS" --timeout 1800)
if [ -n "${SANITIZE_TESTS:-}" ]; then CTEST_ARGS+=(-R "$SANITIZE_TESTS"); fi
# Monte-Carlo tests too slow under ASan at -O1 (minutes; they run in the normal build).
EXCLUDE=${SANITIZE_EXCLUDE-ShadowClassifier.HandheldStaticVsMoving|Consistency.CameraPoseNeesInsideChiSquareBand}
if [ -n "$EXCLUDE" ]; then CTEST_ARGS+=(-E "$EXCLUDE"); fi
ctest "${CTEST_ARGS[@]}"

echo "== sanitize: end-to-end runs ($FRAMES frames of the built-in scene)"
for cfg in ini/single.ini ini/imm7.ini; do
  out="$BUILD/e2e-$(basename "$cfg" .ini)"
  run_e2e() { "$BUILD/bin/imm-monoslam" "$cfg" --frames "$FRAMES" --out "$out" --no-gui --quiet > "$out.log" 2>&1; }
  if ! run_e2e; then
    # LeakSanitizer's own tracer crash (no leak report) is a known intermittent fault of the tool at
    # exit: the run is made once more, and must then pass with its leak check.
    if grep -q "LeakSanitizer has encountered a fatal error" "$out.log" &&
       ! grep -q -E "ERROR: (Address|Leak)Sanitizer|runtime error:" "$out.log"; then
      echo "   $cfg: LeakSanitizer's tracer crashed at exit (no report); running it again"
      run_e2e || { echo "sanitize: end-to-end run with $cfg failed:"; cat "$out.log"; exit 1; }
    else
      echo "sanitize: end-to-end run with $cfg failed:"; cat "$out.log"; exit 1
    fi
  fi
  if grep -q -E "ERROR: (Address|Leak)Sanitizer|runtime error:" "$out.log"; then
    echo "sanitize: sanitizer report in the end-to-end run with $cfg:"; cat "$out.log"; exit 1
  fi
  echo "   $cfg: $(tail -n 1 "$out.log")"
done
# The damaged-input paths too: a truncated rawlog and a dataset folder with a corrupt image.
E2E="$BUILD/e2e-bad"
rm -rf "$E2E"; mkdir -p "$E2E"
"$BUILD/bin/imm-render" ini/scenarios/handheld.ini "$E2E/ds" --frames 30 > /dev/null
printf 'not a png' > "$E2E/ds/rgb/000010.png"
"$BUILD/bin/dataset2rawlog" "$E2E/ds" "$E2E/x.rawlog" --embed > /dev/null
truncate -s $(( $(stat -c %s "$E2E/x.rawlog") * 2 / 3 )) "$E2E/x.rawlog"
for input in "$E2E/ds" "$E2E/x.rawlog"; do
  "$BUILD/bin/imm-monoslam" ini/imm7.ini "$input" --out "$E2E/out" --no-gui --quiet > "$E2E/log" 2>&1 || true
  if grep -q -E "ERROR: (Address|Leak)Sanitizer|runtime error:" "$E2E/log"; then
    echo "sanitize: sanitizer report on damaged input $input:"; cat "$E2E/log"; exit 1
  fi
  echo "   damaged input $(basename "$input"): $(tail -n 1 "$E2E/log" | cut -c1-160)"
done
echo "== sanitize: no sanitizer report ($(( $(date +%s) - T0 )) s)"
