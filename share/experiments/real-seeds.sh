#!/usr/bin/env bash
# The real sequences over RANSAC draws: each configuration run on visp_rbt and monoslam_testseq with
# [slam] seed = 1..N (1-point RANSAC's draws; one run is one draw, and on the 99 frames of visp_rbt one
# draw can lose the path), the ATE after Sim(3) of trajectory.txt and trajectory_smoothed.txt (% of the
# scene's extent) per seed, their median and mean, the runs whose translation is reversed (the median
# direction error of the 6-frame relative motions above 90 deg: the second solution of a mostly planar
# scene, doc/experiments/imm-bank.md), and the shadow filter's decisions (every dynamic decision is
# false on these static scenes).
#   visp_rbt          against VISP_REF (default: its ground truth, the AprilTag poses);
#   monoslam_testseq  against TESTSEQ_REF (default: the bundle adjustment of an independent run's
#                     matches, ini/single.ini's trajectory_refined.txt, made here).
# Usage: share/experiments/real-seeds.sh [--build DIR] [--out DIR] [--seeds LIST] [--data DIR]
#        (defaults: build, /tmp/real-seeds, 1-5, $IMMSLAM_SHARED_DATA_DIR or ../shared/data;
#        share/experiments/args.sh)
# Environment: CONFIGS (default "ini/imm7-shadow.ini ini/imm7.ini"), SET (extra imm-monoslam options
#   for every run), VISP_REF and TESTSEQ_REF (reference trajectories: the COLMAP reconstructions of
#   share/experiments/make-reference.sh, doc/experiments/references.md).
set -euo pipefail
cd "$(dirname "$0")/../.."
source share/experiments/args.sh
source share/experiments/references.sh
mapfile -t SEEDS < <(seq 1 5)
args_parse "$@"
read -r -a CONFIGS <<< "${CONFIGS:-ini/imm7-shadow.ini ini/imm7.ini}"
read -r -a EXTRA <<< "${SET:-}"
APP=$BUILD/bin/imm-monoslam
EVAL=$BUILD/bin/slam-eval
mkdir -p "$OUT"
for seq in visp_rbt monoslam_testseq; do
  [ -d "$DATA/$seq" ] || { echo "real-seeds: $DATA/$seq not found (--data)" >&2; exit 1; }
done

score() {  # EST REF -> "EXTENT REVERSED": ATE % of extent (- when the file is missing) and 1 if the median
           # direction error of the 6-frame motions exceeds 90 deg, else 0 (one evaluation)
  [ -s "$1" ] || { echo "- 0"; return; }
  "$EVAL" ate "$1" "$2" --rpe 6 | awk '/ATE \/ extent/ { e = sprintf("%.2f", $(NF - 1)) }
    /RPE direction/ { r = ($4 == "median" && $5 > 90) } END { print (e == "" ? "-" : e), r + 0 }'
}
stats() {  # VALUES... -> "median M mean A" (values that are - are left out)
  printf '%s\n' "$@" | grep -v '^-$' | sort -g |
    awk '{ v[NR] = $1; s += $1 } END { if (NR) printf "median %.2f mean %.2f", (NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2), s / NR; else printf "-" }'
}

VREF=${VISP_REF:-$DATA/visp_rbt/groundtruth.txt}
TREF=$(testseq_reference "$OUT")

for cfg in "${CONFIGS[@]}"; do
  for seq in visp_rbt monoslam_testseq; do
    ref=$VREF
    [ "$seq" = monoslam_testseq ] && ref=$TREF
    filt=() smo=() dyn=0 all=0 rev=0
    for s in "${SEEDS[@]}"; do
      o="$OUT/$(basename "$cfg" .ini)-$seq-$s"
      "$APP" "$cfg" "$DATA/$seq" --out "$o" --no-gui --quiet --set output.scene=false --set "slam.seed=$s" \
        "${EXTRA[@]}" > "$o.log" 2>&1 || true
      read -r e r < <(score "$o/trajectory.txt" "$ref")
      filt+=("$e")
      rev=$((rev + r))
      read -r e _ < <(score "$o/trajectory_smoothed.txt" "$ref")
      smo+=("$e")
      if [ -s "$o/classifications.csv" ]; then
        dyn=$((dyn + $(awk -F, 'NR > 1 && $3 == "dynamic"' "$o/classifications.csv" | wc -l)))
        all=$((all + $(awk -F, 'NR > 1' "$o/classifications.csv" | wc -l)))
      fi
    done
    printf '%-20s %-17s filter %s (%s) | smoothed %s (%s) | reversed %d of %d | dynamic decisions %d of %d\n' \
      "$(basename "$cfg")" "$seq" "${filt[*]}" "$(stats "${filt[@]}")" "${smo[*]}" "$(stats "${smo[@]}")" \
      "$rev" "${#SEEDS[@]}" "$dyn" "$all"
  done
done
