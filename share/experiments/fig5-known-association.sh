#!/usr/bin/env bash
# The MonoSLAMBOT paper's Fig. 5 experiment as published: data association "performed manually"
# ([input] known_association with the point tracks of `imm-render --points`), on the rendered hand-held
# path with moving boxes (doc/shadow.md, "Fig. 5 with known data association"). Per seed, ATE (% of
# path) with the dynamic points disabled ("static") and with all points ("all"):
#   paper protocol (no RANSAC, static first map, no release): single.ini (a)/(b), single-shadow.ini (c),
#   imm7-shadow.ini;
#   the system's own protocol (gate, RANSAC, deletion, handovers): imm7-shadow.ini (the full system).
# The last line gives the means and the ratios all/static.
# Usage: share/experiments/fig5-known-association.sh [--build DIR] [--out DIR] [--seeds LIST]
#        (defaults: build, /tmp/fig5-ka, 7,11,23,42,101; LIST as 101-140 or 7,11,23; share/experiments/args.sh)
set -euo pipefail
cd "$(dirname "$0")/../.."
source share/experiments/args.sh
ARGS_COMMON="--build --out --seeds"
OUT=/tmp/fig5-ka
SEEDS=(7 11 23 42 101)
args_parse "$@"
mkdir -p "$OUT"
# (The paper's filter decides a point that moves alone at once: shadow.decide_lone_dynamic.)
PAPER=(--set input.known_association_robust=false --set input.known_association_first_map=static --set system.starved_below=0
       --set shadow.decide_lone_dynamic=true)
run() {  # run NAME CONFIG DATA KINDS [args...]
  "$BUILD/bin/imm-monoslam" "ini/$2.ini" "$3" --out "$OUT/out-$1" --no-gui --quiet \
    --set output.scene=false --set "input.known_association=$3/points_groundtruth.txt" \
    --set "input.known_association_kinds=$4" "${@:5}" | grep -o '= [0-9.]* % of path' | head -n 1 | tr -dc '0-9.'
}
COLS=(single/static single/all single-shadow/static single-shadow/all imm7-shadow/static imm7-shadow/all
      full-own/static full-own/all)
echo "seed  ${COLS[*]}"
ROWS=$(mktemp)
trap 'rm -f "$ROWS"' EXIT
for s in "${SEEDS[@]}"; do
  d="$OUT/handheld-moving-$s"
  [ -s "$d/points_groundtruth.txt" ] || "$BUILD/bin/imm-render" ini/scenarios/handheld-moving.ini "$d" --seed "$s" --points 200 > /dev/null
  row="$s"
  for cfg in single single-shadow imm7-shadow; do
    for k in static all; do row="$row $(run "$cfg-$k-$s" "$cfg" "$d" "$k" "${PAPER[@]}")"; done
  done
  for k in static all; do row="$row $(run "own-$k-$s" imm7-shadow "$d" "$k")"; done
  echo "$row" | tee -a "$ROWS"
done
awk '{for (i = 2; i <= NF; i++) m[i] += $i} END {printf "mean "; for (i = 2; i <= NF; i++) printf " %.3f", m[i] / NR;
     printf "\nall/static: single %.2f, single-shadow %.2f, imm7-shadow %.2f, full system (own protocol) %.2f\n",
     m[3] / m[2], m[5] / m[4], m[7] / m[6], m[9] / m[8]}' "$ROWS"
