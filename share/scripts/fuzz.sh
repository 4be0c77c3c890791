#!/usr/bin/env bash
# Coverage-guided fuzzing of the parsers (issue 8) with libFuzzer: builds tests/fuzz with clang,
# AddressSanitizer + UndefinedBehaviorSanitizer and libFuzzer instrumentation of the libraries, then
# runs each target for SECONDS seconds on its committed seeds (tests/fuzz/corpus/<target>) plus the
# corpus it grows in the build folder. A crash, leak, timeout or out-of-memory fails the script; the
# input is kept in BUILD/fuzz-artifacts/<target>/: fix the bug, then copy the input into
# tests/fuzz/regressions/<target>/ (fuzz_regression_unittest runs it in every build).
#
# Usage: share/scripts/fuzz.sh [SECONDS] [TARGET...]
#   SECONDS  per target (default 60); TARGET among calib dataset ini rawlog (default all)
# Environment: FUZZ_BUILD_DIR (default build-fuzz), JOBS (build jobs, default nproc),
#   FUZZ_ARGS (extra libFuzzer options), CC/CXX (default clang/clang++).
set -euo pipefail
cd "$(dirname "$0")/../.."
ROOT=$(pwd)
SECS=${1:-60}
[ $# -gt 0 ] && shift
TARGETS=("$@")
[ ${#TARGETS[@]} -eq 0 ] && TARGETS=(calib dataset ini rawlog)
BUILD=${FUZZ_BUILD_DIR:-build-fuzz}
JOBS=${JOBS:-$(nproc)}
export CC=${CC:-clang} CXX=${CXX:-clang++}
T0=$(date +%s)

if ! command -v "$CXX" > /dev/null; then
  echo "fuzz: $CXX not found (Debian: apt-get install clang libclang-rt-14-dev)"; exit 1
fi

echo "== fuzz: configure $BUILD ($CXX, ASan + UBSan + libFuzzer instrumentation, -O1)"
mkdir -p "$BUILD"
cmake -S . -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" \
  -DCMAKE_CXX_FLAGS="-fsanitize=fuzzer-no-link,address,undefined -Wno-unknown-warning-option" -DIMMSLAM_SANITIZE=ON \
  -DIMMSLAM_BUILD_FUZZERS=ON -DIMMSLAM_BUILD_BENCHMARKS=OFF -DIMMSLAM_BUILD_TESTS=ON > "$BUILD/configure.log"
BINS=()
for t in "${TARGETS[@]}"; do BINS+=("fuzz_$t"); done
echo "== fuzz: building ${BINS[*]}"
cmake --build "$BUILD" -j"$JOBS" --target "${BINS[@]}"

# MRPT and OpenCV are not instrumented; leaks inside them (e.g. plugin loaders) would be reported
# against our inputs, so they are suppressed by library name. Big allocations asked by a corrupt
# size field (MRPT allocates what the field says before reading) must fail as a clean error:
# operator new above 256 MiB throws std::bad_alloc (tests/fuzz/fuzz_alloc_limit.cpp) and malloc
# above 2 GiB returns null (OpenCV then throws), below libFuzzer's own malloc limit.
SUPP="$ROOT/$BUILD/fuzz-lsan.supp"
printf 'leak:libmrpt\nleak:libopencv\nleak:libgdal\n' > "$SUPP"
export ASAN_OPTIONS="allocator_may_return_null=1:max_allocation_size_mb=2048:detect_leaks=1:handle_abort=1:print_summary=1"
export LSAN_OPTIONS="suppressions=$SUPP:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
for s in llvm-symbolizer /usr/lib/llvm-14/bin/llvm-symbolizer llvm-symbolizer-14; do
  if command -v "$s" > /dev/null; then export ASAN_SYMBOLIZER_PATH; ASAN_SYMBOLIZER_PATH=$(command -v "$s"); break; fi
done

failed=()
for t in "${TARGETS[@]}"; do
  corpus="$BUILD/fuzz-corpus/$t"; art="$BUILD/fuzz-artifacts/$t/"
  mkdir -p "$corpus" "$art"
  dict=()
  [ -f "tests/fuzz/$t.dict" ] && dict=(-dict="tests/fuzz/$t.dict")
  echo "== fuzz: $t for $SECS s"
  # shellcheck disable=SC2086
  if "$BUILD/fuzz/fuzz_$t" "$corpus" "tests/fuzz/corpus/$t" "${dict[@]}" -max_total_time="$SECS" \
      -timeout=20 -rss_limit_mb=3072 -malloc_limit_mb=4096 -max_len=65536 -print_final_stats=1 \
      -artifact_prefix="$art" ${FUZZ_ARGS:-} > "$BUILD/fuzz-$t.log" 2>&1; then
    echo "   $t: $(grep -E '^stat::number_of_executed_units' "$BUILD/fuzz-$t.log" | awk '{print $2}') runs," \
         "corpus $(find "$corpus" -type f | wc -l) inputs, $(grep -o 'cov: [0-9]*' "$BUILD/fuzz-$t.log" | tail -n 1)"
  else
    failed+=("$t")
    echo "   $t: FAILED; last lines of $BUILD/fuzz-$t.log:"
    grep -v -E '^#[0-9]+' "$BUILD/fuzz-$t.log" | tail -n 40
    echo "   inputs: $(ls "$art")"
  fi
done
echo "== fuzz: done in $(( $(date +%s) - T0 )) s"
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz: failures in ${failed[*]}: inputs in $BUILD/fuzz-artifacts/<target>/ (reproduce:" \
       "$BUILD/fuzz/fuzz_<target> INPUT; keep it in tests/fuzz/regressions/<target>/ once fixed)"
  exit 1
fi
