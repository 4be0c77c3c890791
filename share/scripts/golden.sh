#!/usr/bin/env bash
# Golden outputs: runs imm-monoslam on a small fixed set of inputs (tests/golden/cases.txt) and
# compares trajectory.txt, model_probabilities.csv, classifications.csv, tracks.csv and map.csv byte
# for byte with the recorded copies in tests/golden/<case>/. Any change of behaviour, however small,
# shows here; a change that is meant re-records them (and its measured effect goes in the commit).
#
# Usage: share/scripts/golden.sh check|record|list [--build DIR] [CASE...]
#   check    run the cases (default all) and compare; exit 1 on a difference, 77 when every case
#            asked for needs ../shared/data and it is absent (ctest: skipped)
#   record   run the cases and copy their outputs into tests/golden/<case>/ (the re-record command)
#   list     print the case names
#   --build  the Release build folder with bin/imm-monoslam and bin/imm-render (default build)
# The renders are kept in BUILD/golden/render/ (made once per build folder, under a lock, so ctest -j
# can run the cases in parallel); outputs go to BUILD/golden/out/<case>/.
# Golden files are bitwise results of one compiler and flag set (Debian 12's gcc, CMake Release):
# ctest registers the cases only in such a build (not the sanitizer or fuzz builds).
set -euo pipefail
cd "$(dirname "$0")/../.."
ROOT=$(pwd)
CASES_FILE="$ROOT/tests/golden/cases.txt"
FILES=(trajectory.txt model_probabilities.csv classifications.csv tracks.csv map.csv)

usage() { sed -n '2,17p' "$0" | sed 's/^# \{0,1\}//'; exit 2; }
[ $# -ge 1 ] || usage
MODE=$1; shift
case "$MODE" in check|record|list) ;; -h|--help) usage ;; *) echo "golden: unknown mode '$MODE'" >&2; usage ;; esac
BUILD=build
SELECT=()
while [ $# -gt 0 ]; do
  case "$1" in
    --build) [ $# -ge 2 ] || usage; BUILD=$2; shift 2 ;;
    --build=*) BUILD=${1#--build=}; shift ;;
    -*) echo "golden: unknown option '$1'" >&2; usage ;;
    *) SELECT+=("$1"); shift ;;
  esac
done
case "$BUILD" in /*) ;; *) BUILD="$ROOT/$BUILD" ;; esac
DATA=${IMMSLAM_SHARED_DATA_DIR:-$ROOT/../shared/data}

# The cases: one "name config input options..." per line, '#' comments.
mapfile -t LINES < <(grep -v '^[[:space:]]*\(#\|$\)' "$CASES_FILE")
names=()
for l in "${LINES[@]}"; do read -r n _ <<< "$l"; names+=("$n"); done
if [ "$MODE" = list ]; then printf '%s\n' "${names[@]}"; exit 0; fi
if [ ${#SELECT[@]} -eq 0 ]; then SELECT=("${names[@]}"); fi
for s in "${SELECT[@]}"; do
  printf '%s\n' "${names[@]}" | grep -qx -- "$s" || { echo "golden: no case '$s' in $CASES_FILE" >&2; exit 2; }
done

APP="$BUILD/bin/imm-monoslam"
RENDER="$BUILD/bin/imm-render"
for b in "$APP" "$RENDER"; do
  [ -x "$b" ] || { echo "golden: $b not found: build first (cmake --build $BUILD)" >&2; exit 2; }
done

# Renders input token render:SCENARIO:SEED:FRAMES once per build folder; prints the folder.
render_input() {
  local scen seed frames points dir extra=()
  IFS=: read -r _ scen seed frames points <<< "$1"
  dir="$BUILD/golden/render/$scen-$seed-$frames${points:+-p$points}"
  [ -z "$points" ] || extra=(--points "$points")
  mkdir -p "$BUILD/golden/render"
  (
    flock 9
    if [ ! -f "$dir/.done" ]; then
      rm -rf "$dir"
      "$RENDER" "$ROOT/ini/scenarios/$scen.ini" "$dir" --seed "$seed" --frames "$frames" "${extra[@]}" > "$dir.log" 2>&1 \
        || { echo "golden: imm-render failed for $1 (log: $dir.log)" >&2; exit 1; }
      touch "$dir/.done"
    fi
  ) 9> "$dir.lock"
  echo "$dir"
}

# Compares one output file with its golden copy; prints where they first differ.
compare_file() {
  local got=$1 want=$2 name=$3
  if [ ! -e "$want" ] && [ ! -e "$got" ]; then return 0; fi
  if [ ! -e "$want" ]; then echo "  $name: produced but not in the golden set"; return 1; fi
  if [ ! -e "$got" ]; then echo "  $name: in the golden set but not produced"; return 1; fi
  if cmp -s "$got" "$want"; then return 0; fi
  local nl_got nl_want
  nl_got=$(wc -l < "$got"); nl_want=$(wc -l < "$want")
  echo "  $name differs ($nl_got lines, golden $nl_want); first differing lines (golden <, now >):"
  diff "$want" "$got" | head -n 6 | sed 's/^/    /'
  if [ "$name" = trajectory.txt ] && [ "$nl_got" = "$nl_want" ]; then
    # Largest position difference, to tell a last-bit change from a different run.
    paste -d' ' "$want" "$got" | awk '!/^#/ { d = 0; for (i = 2; i <= 4; ++i) { x = $i - $(i + 8); d += x * x }
        if (d > m) m = d } END { printf "    largest position difference %.3g\n", sqrt(m) }'
  fi
  return 1
}

failed=0; ran=0; skipped=0
for l in "${LINES[@]}"; do
  read -r name cfg input opts <<< "$l"
  printf '%s\n' "${SELECT[@]}" | grep -qx -- "$name" || continue
  case "$input" in
    render:*) in_path=$(render_input "$input") ;;
    data:*)
      in_path="$DATA/${input#data:}"
      if [ ! -d "$in_path" ]; then
        echo "golden: $name skipped: $in_path absent"; skipped=$((skipped + 1)); continue
      fi ;;
    *) echo "golden: $name: unknown input '$input' in $CASES_FILE" >&2; exit 2 ;;
  esac
  opts=${opts//\{input\}/$in_path}
  out="$BUILD/golden/out/$name"
  rm -rf "$out"; mkdir -p "$out"
  # shellcheck disable=SC2086  # the case's options are words
  if ! "$APP" "$ROOT/ini/$cfg.ini" "$in_path" --out "$out" --no-gui --quiet \
      --set output.scene=false --set slam.num_threads=2 $opts > "$out/run.log" 2>&1; then
    echo "golden: $name: imm-monoslam failed (log: $out/run.log)"; tail -n 5 "$out/run.log"; failed=$((failed + 1)); continue
  fi
  ran=$((ran + 1))
  want_dir="$ROOT/tests/golden/$name"
  if [ "$MODE" = record ]; then
    rm -rf "$want_dir"; mkdir -p "$want_dir"
    for f in "${FILES[@]}"; do [ -e "$out/$f" ] && cp "$out/$f" "$want_dir/$f"; done
    echo "golden: $name recorded ($(ls "$want_dir" | tr '\n' ' '))"
    continue
  fi
  bad=0
  for f in "${FILES[@]}"; do compare_file "$out/$f" "$want_dir/$f" "$f" || bad=1; done
  if [ $bad -eq 0 ]; then echo "golden: $name identical"; else
    echo "golden: $name DIFFERS from tests/golden/$name (outputs in $out; re-record with share/scripts/golden.sh record $name if the change is meant)"
    failed=$((failed + 1))
  fi
done

[ $failed -eq 0 ] || exit 1
if [ $ran -eq 0 ] && [ $skipped -gt 0 ]; then exit 77; fi
exit 0
