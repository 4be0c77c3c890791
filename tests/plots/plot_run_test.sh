#!/usr/bin/env bash
# plot_run_test.sh IMM_MONOSLAM SOURCE_DIR OUT_DIR [PYTHON]: runs 60 frames of the rendered hand-held
# scenario (true motion labels and ground truth: every figure has its data), then
# share/scripts/plot-run.py on the output folder; fails unless every figure is a non-empty PNG.
set -uo pipefail
APP="$1"; SRC="$2"; OUT="$3"; PY_CMAKE="${4:-}"
fail() { echo "FAIL: $*" >&2; exit 1; }

PY=""
for p in "$PY_CMAKE" python3 /usr/bin/python3; do
  [[ -n "$p" ]] && command -v "$p" > /dev/null && "$p" -c "import matplotlib" 2> /dev/null && { PY="$p"; break; }
done
if [[ -z "$PY" ]]; then
  echo "SKIP: no python3 with matplotlib (Debian: apt-get install python3-matplotlib)"
  exit 77
fi

rm -rf "$OUT"; mkdir -p "$OUT"
"$APP" "$SRC/ini/imm7.ini" --set input.scenario=scenarios/handheld.ini --frames 60 --out "$OUT/run" \
  --no-gui --quiet --set output.scene=false > "$OUT/run.log" 2>&1 || { tail -5 "$OUT/run.log"; fail "imm-monoslam failed"; }
for f in model_probabilities.csv frame_stats.csv motion_labels.csv ate.csv; do
  [[ -s "$OUT/run/$f" ]] || fail "the run wrote no $f"
done
[[ "$(head -1 "$OUT/run/motion_labels.csv")" == "timestamp,label" ]] || fail "motion_labels.csv header"
[[ "$(head -1 "$OUT/run/ate.csv")" == "timestamp,position_error" ]] || fail "ate.csv header"
[[ $(wc -l < "$OUT/run/motion_labels.csv") == $(wc -l < "$OUT/run/model_probabilities.csv") ]] ||
  fail "motion_labels.csv has not one row per frame of model_probabilities.csv"

"$PY" "$SRC/share/scripts/plot-run.py" "$OUT/run" --out "$OUT/figures" > "$OUT/plot.log" 2>&1 ||
  { cat "$OUT/plot.log"; fail "plot-run.py failed"; }
for f in model_probabilities.png model_probabilities_log.png search_area.png ate.png; do
  [[ -s "$OUT/figures/$f" ]] || fail "plot-run.py wrote no $f"
  [[ "$(head -c 8 "$OUT/figures/$f" | od -An -tx1 | tr -d ' \n')" == "89504e470d0a1a0a" ]] || fail "$f is not a PNG"
done

# A malformed file is an error naming it.
mkdir -p "$OUT/bad"; printf 'timestamp,general\n0.0,abc\n' > "$OUT/bad/model_probabilities.csv"
if "$PY" "$SRC/share/scripts/plot-run.py" "$OUT/bad" > "$OUT/bad.log" 2>&1; then fail "plot-run.py accepted a malformed CSV"; fi
grep -q "model_probabilities.csv:2: 'abc' is not a number" "$OUT/bad.log" || { cat "$OUT/bad.log"; fail "error message"; }

# The removed key names the script.
if "$APP" "$SRC/ini/single.ini" --set input.scenario=scenarios/handheld.ini --frames 2 --out "$OUT/old" --no-gui \
    --quiet --set output.plots=false > "$OUT/old.log" 2>&1; then
  fail "[output] plots was accepted"
fi
grep -q "\[output\] plots: removed.*plot-run.py" "$OUT/old.log" || { cat "$OUT/old.log"; fail "removed-key message"; }
echo "OK: $(ls "$OUT/figures" | tr '\n' ' ')"
