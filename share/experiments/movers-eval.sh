#!/usr/bin/env bash
# Moving objects outside MonoSLAMBOT's assumptions, on a rendered scene family (doc/shadow.md): per
# seed, the full system's decisions against the renderer's masks of what moves (static -> dynamic and
# moving -> static, counts), its ATE (% of path) with the objects and on the same path and world
# without them ([objects] enabled = false), and the IMM without the shadow filter in that static
# world; then the totals and means.
# Usage: share/experiments/movers-eval.sh SCENARIO.ini [--build DIR] [--out DIR] [--seeds LIST]
#        (defaults: build, /tmp/movers-eval, 101-140; LIST as 101-140 or 7,11,23; share/experiments/args.sh)
# Environment: CONFIG (default ini/imm7-shadow.ini), BASE_CONFIG (default ini/imm7.ini), SET (extra
#   imm-monoslam options for both, e.g. "--set system.watch_features=0"), APP (the imm-monoslam to run,
#   default BUILD_DIR/bin/imm-monoslam: another build on the same renders).
set -euo pipefail
cd "$(dirname "$0")/../.."
source share/experiments/args.sh
ARGS_COMMON="--build --out --seeds"
ARGS_NPOS=1 ARGS_POS_NAMES=SCENARIO.ini
mapfile -t SEEDS < <(seq 101 140)
args_parse "$@"
SCEN=${POS[0]}
[ -f "$SCEN" ] || args_die "scenario '$SCEN' not found"
CONFIG=${CONFIG:-ini/imm7-shadow.ini}
BASE_CONFIG=${BASE_CONFIG:-ini/imm7.ini}
read -r -a EXTRA <<< "${SET:-}"
APP=${APP:-$BUILD/bin/imm-monoslam}
name=$(basename "$SCEN" .ini)
mkdir -p "$OUT"

run() {  # CONFIG INPUT OUT -> prints ATE % of path
  "$APP" "$1" "$2" --out "$3" --no-gui --quiet --set output.scene=false \
    "${EXTRA[@]}" > "$3.log" 2>&1 || { echo nan; return; }
  grep -o '= [0-9.]* % of path' "$3.log" | head -n 1 | tr -dc '0-9.'
}
count() {  # CLASSIFICATIONS MASK_FOLDER -> "static->dynamic static_total moving->static moving_total"
  if [ ! -s "$1" ]; then echo "0 0 0 0"; return; fi
  local c ms sd
  c=$("$BUILD/bin/slam-eval" classification "$1" --masks "$2")
  # Lines such as "moving->static rate : 0.00 % (0/12)".
  ms=$(grep 'moving->static rate' <<< "$c" | sed -n 's/.*(\([0-9]*\)\/\([0-9]*\)).*/\1 \2/p')
  sd=$(grep 'static->dynamic rate' <<< "$c" | sed -n 's/.*(\([0-9]*\)\/\([0-9]*\)).*/\1 \2/p')
  echo "${sd:-0 0} ${ms:-0 0}"
}

printf '%-6s %-8s %-8s %-8s %-8s %-9s %-9s %-9s %s\n' seed 's->d' static 'm->s' moving ate_movers ate_static imm7_static ratio
tot_sd=0 tot_s=0 tot_ms=0 tot_m=0
rows=$(mktemp); trap 'rm -f "$rows"' EXIT
for s in "${SEEDS[@]}"; do
  mov="$OUT/$name-$s"; sta="$OUT/$name-static-$s"
  [ -f "$mov/rgb.txt" ] || "$BUILD/bin/imm-render" "$SCEN" "$mov" --seed "$s" > /dev/null
  [ -f "$sta/rgb.txt" ] || "$BUILD/bin/imm-render" "$SCEN" "$sta" --seed "$s" --set objects.enabled=false > /dev/null
  a=$(run "$CONFIG" "$mov" "$OUT/out-$name-$s")
  b=$(run "$CONFIG" "$sta" "$OUT/out-$name-static-$s")
  c=$(run "$BASE_CONFIG" "$sta" "$OUT/out-$name-static-base-$s")
  read -r sd st ms mt <<< "$(count "$OUT/out-$name-$s/classifications.csv" "$mov")"
  tot_sd=$((tot_sd + sd)); tot_s=$((tot_s + st)); tot_ms=$((tot_ms + ms)); tot_m=$((tot_m + mt))
  r=$(awk -v a="$a" -v b="$b" 'BEGIN { printf (b > 0 ? "%.2f" : "-"), a / b }')
  printf '%-6s %-8s %-8s %-8s %-8s %-9s %-9s %-9s %s\n' "$s" "$sd" "$st" "$ms" "$mt" "$a" "$b" "$c" "$r"
  echo "$a $b $c" >> "$rows"
done
awk -v sd="$tot_sd" -v st="$tot_s" -v ms="$tot_ms" -v mt="$tot_m" '
  { a += $1; b += $2; c += $3; n++; if ($1 > 2) fa++; if ($2 > 2) fb++ }
  END {
    printf "decisions: static->dynamic %d / %d (%.1f %%), moving->static %d / %d (%.1f %%)\n",
      sd, st, st ? 100 * sd / st : 0, ms, mt, mt ? 100 * ms / mt : 0
    printf "ATE %% of path, mean over %d seeds: with movers %.3f, static world %.3f (ratio %.2f), IMM alone static %.3f; runs > 2 %%: %d / %d\n",
      n, a / n, b / n, (b > 0 ? a / b : 0), c / n, fa, fb
  }' "$rows"
