#!/usr/bin/env bash
# Mutation check: applies each known-bad change of tests/mutation/*.patch to a scratch copy of the
# source tree, rebuilds only the targets that patch names, runs the tests that must catch it, and
# fails if any mutant survives (its tests all pass). The working tree is never modified.
#
# Usage: share/scripts/mutation.sh [MUTANT...]      (default: every tests/mutation/*.patch)
# Environment: MUTATION_DIR (scratch folder, default build-mutation), JOBS (default nproc),
#   MUTATION_TEST_TIMEOUT (seconds per test, default 300).
#
# A mutant is a unified diff (patch -p1 at the repository root) after three header lines:
#   # mutant: what the change breaks
#   # build: cmake targets to rebuild (the test programs that must catch it)
#   # kill: ctest -R regular expression of the tests of which at least one must fail
# Before the mutants, the same tests run on the unmutated copy and must all pass. A patch that no
# longer applies, or a mutant that no longer compiles, is an error: update it with the code.
# ccache (when installed) makes the scratch build reuse the main build's library objects.
set -euo pipefail
cd "$(dirname "$0")/../.."
ROOT=$(pwd)
WORK=${MUTATION_DIR:-build-mutation}
case "$WORK" in /*) ;; *) WORK="$ROOT/$WORK" ;; esac
JOBS=${JOBS:-$(nproc)}
TEST_TIMEOUT=${MUTATION_TEST_TIMEOUT:-300}
SRC="$WORK/src"
BUILD="$SRC/build"
T0=$(date +%s)

mutants=()
if [ $# -gt 0 ]; then
  for m in "$@"; do
    f="$ROOT/tests/mutation/${m%.patch}.patch"
    [ -f "$f" ] || { echo "mutation: no $f" >&2; exit 2; }
    mutants+=("$f")
  done
else
  mutants=("$ROOT"/tests/mutation/*.patch)
fi
[ -f "${mutants[0]}" ] || { echo "mutation: no tests/mutation/*.patch" >&2; exit 2; }

header() { sed -n "s/^# $1: *//p" "$2" | head -n 1; }

# Scratch copy of the tracked and new (not ignored) files, every file with a new time: an object
# built from a mutant in an earlier run must not look newer than its restored source (ccache makes
# the rebuild cheap).
echo "== mutation: scratch copy in $SRC"
mkdir -p "$SRC"
find "$SRC" -mindepth 1 -maxdepth 1 ! -name build -exec rm -rf {} +
git ls-files -co --exclude-standard -z | tar --null -T - -cf - | tar -xmf - -C "$SRC"

launcher=()
if command -v ccache > /dev/null; then
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  export CCACHE_BASEDIR="$ROOT"
fi
cmake -S "$SRC" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DIMMSLAM_BUILD_BENCHMARKS=OFF \
  -DIMMSLAM_SHARED_DATA_DIR="$ROOT/../shared/data" "${launcher[@]}" > "$WORK/configure.log" \
  || { cat "$WORK/configure.log"; exit 1; }

# Runs the tests matching $1; prints "total failed".
run_tests() {
  local log=$2 summary
  ctest --test-dir "$BUILD" -R "$1" --timeout "$TEST_TIMEOUT" -j"$JOBS" > "$log" 2>&1 || true
  summary=$(grep -E 'tests passed, [0-9]+ tests? failed out of [0-9]+' "$log" | tail -n 1)
  if [ -z "$summary" ]; then echo "0 0"; return; fi
  echo "$(sed -E 's/.* out of ([0-9]+).*/\1/' <<< "$summary") $(sed -E 's/.*passed, ([0-9]+) tests? failed.*/\1/' <<< "$summary")"
}

# The targets and tests every mutant needs, built and run once unmutated.
all_targets=(); all_kill=()
for m in "${mutants[@]}"; do
  b=$(header build "$m"); k=$(header kill "$m")
  [ -n "$b" ] && [ -n "$k" ] || { echo "mutation: $m lacks its '# build:' or '# kill:' line" >&2; exit 2; }
  read -r -a t <<< "$b"; all_targets+=("${t[@]}"); all_kill+=("$k")
done
mapfile -t all_targets < <(printf '%s\n' "${all_targets[@]}" | sort -u)
echo "== mutation: building ${all_targets[*]}"
cmake --build "$BUILD" -j"$JOBS" --target "${all_targets[@]}" > "$WORK/build.log" 2>&1 \
  || { tail -n 40 "$WORK/build.log"; echo "mutation: the unmutated copy does not build"; exit 1; }
kill_all=$(IFS='|'; echo "${all_kill[*]}")
read -r total nfail <<< "$(run_tests "$kill_all" "$WORK/baseline.log")"
if [ "$total" -eq 0 ] || [ "$nfail" -ne 0 ]; then
  tail -n 30 "$WORK/baseline.log"
  echo "mutation: the unmutated tests must all pass ($nfail of $total failed)"; exit 1
fi
echo "== mutation: baseline $total tests pass ($(( $(date +%s) - T0 )) s)"

survivors=0; errors=0
for m in "${mutants[@]}"; do
  name=$(basename "$m" .patch)
  desc=$(header mutant "$m"); read -r -a targets <<< "$(header build "$m")"; kill=$(header kill "$m")
  t1=$(date +%s)
  if ! patch -s -p1 -d "$SRC" --no-backup-if-mismatch < "$m" > "$WORK/$name.patch.log" 2>&1; then
    echo "ERROR   $name: the patch no longer applies (update tests/mutation/$name.patch)"; errors=$((errors + 1))
    patch -s -R -p1 -d "$SRC" --no-backup-if-mismatch < "$m" > /dev/null 2>&1 || true
    continue
  fi
  if ! cmake --build "$BUILD" -j"$JOBS" --target "${targets[@]}" > "$WORK/$name.build.log" 2>&1; then
    echo "ERROR   $name: the mutant does not compile (log: $WORK/$name.build.log)"; errors=$((errors + 1))
  else
    read -r total nfail <<< "$(run_tests "$kill" "$WORK/$name.test.log")"
    if [ "$total" -eq 0 ]; then
      echo "ERROR   $name: '$kill' selects no test"; errors=$((errors + 1))
    elif [ "$nfail" -gt 0 ]; then
      killers=$(grep -E '^\s+[0-9]+ - .*\((Failed|Timeout|SEGFAULT|Subprocess aborted|Exception|Child aborted)' "$WORK/$name.test.log" \
        | sed -E 's/^\s+[0-9]+ - ([^ ]+).*/\1/' | head -n 3 | tr '\n' ' ')
      echo "killed  $name ($desc): $nfail of $total failed, e.g. $killers[$(( $(date +%s) - t1 )) s]"
    else
      echo "SURVIVED $name ($desc): all $total tests of '$kill' pass"; survivors=$((survivors + 1))
    fi
  fi
  patch -s -R -p1 -d "$SRC" --no-backup-if-mismatch < "$m" > /dev/null
done

echo "== mutation: ${#mutants[@]} mutants, $survivors survived, $errors errors, $(( $(date +%s) - T0 )) s"
[ $survivors -eq 0 ] && [ $errors -eq 0 ]
