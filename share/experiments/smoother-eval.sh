#!/usr/bin/env bash
# The online keyframe smoother and the offline refinement against the filter ([output]
# smooth_trajectory, refine_trajectory; doc/experiments/smoother.md): ATE after Sim(3) of
# trajectory.txt, trajectory_smoothed.txt and trajectory_refined.txt of one run per input.
#   visp_rbt          against its ground truth (AprilTag poses), % of path and % of extent;
#   monoslam_testseq  (no ground truth) against the bundle adjustment of an independent run's
#                     matches (ini/single.ini, its trajectory_refined.txt), % of extent;
#   hold-out seeds    ini/scenarios/holdout/pause-pan-movers.ini rendered without its moving objects
#                     (a static world), against the renderer's truth, % of path.
# Also the smoother's lag and CPU share, and the filter's median frame time of each run.
# Usage: share/experiments/smoother-eval.sh [--build DIR] [--out DIR] [--seeds LIST] [--data DIR]
#        (defaults: build, /tmp/smoother-eval, 101-120, $IMMSLAM_SHARED_DATA_DIR or ../shared/data;
#        LIST as 101-140 or 7,11,23; share/experiments/args.sh)
# Environment: CONFIG (default ini/imm7-shadow.ini), SET (extra imm-monoslam options), VISP_REF and
# TESTSEQ_REF (reference trajectories to use instead: the COLMAP reconstructions of
# share/experiments/make-reference.sh, doc/experiments/references.md), STATIC_SCENARIO (default
# ini/scenarios/holdout/pause-pan-movers.ini).
set -euo pipefail
cd "$(dirname "$0")/../.."
source share/experiments/args.sh
source share/experiments/references.sh
mapfile -t SEEDS < <(seq 101 120)
args_parse "$@"
CONFIG=${CONFIG:-ini/imm7-shadow.ini}
read -r -a EXTRA <<< "${SET:-}"
APP=$BUILD/bin/imm-monoslam
EVAL=$BUILD/bin/slam-eval
mkdir -p "$OUT"

run() {  # CONFIG INPUT OUT: a run with both refinements; the log in OUT.log
  "$APP" "$1" "$2" --out "$3" --no-gui --set output.scene=false \
    --set output.refine_trajectory=true --set output.smooth_trajectory=true "${EXTRA[@]}" > "$3.log" 2>&1
}
ate() {  # EST REF -> "% of path  % of extent"
  "$EVAL" ate "$1" "$2" | awk '/ATE \/ path/ { p = $(NF - 1) } /ATE \/ extent/ { e = $(NF - 1) } END { print p, e }'
}
timing() {  # LOG -> "median_ms lag_median lag_max cpu_share"
  local ms lag
  ms=$(grep -o 'median [0-9.]* ms/frame' "$1" | head -n 1 | tr -dc '0-9.')
  lag=$(grep -o 'lag median [0-9.]* frames, max [0-9.]*; smoother CPU [0-9.]* s ([0-9.]* %' "$1" |
        awk '{ print $3, $6, $11 }' | tr -d '(;')
  echo "$ms $lag"
}

printf '%-22s %-24s %-24s %-24s %s\n' input 'filter path/extent %' 'smoothed path/extent %' 'refined path/extent %' \
  'ms/frame lag_med lag_max cpu%'
# visp_rbt against its ground truth.
o="$OUT/visp_rbt"
run "$CONFIG" "$DATA/visp_rbt" "$o"
gt="${VISP_REF:-$DATA/visp_rbt/groundtruth.txt}"
printf '%-22s %-24s %-24s %-24s %s\n' visp_rbt "$(ate "$o/trajectory.txt" "$gt")" \
  "$(ate "$o/trajectory_smoothed.txt" "$gt")" "$(ate "$o/trajectory_refined.txt" "$gt")" "$(timing "$o.log")"
# monoslam_testseq against the refinement of an independent run (single model).
r=$(testseq_reference "$OUT")
o="$OUT/testseq"
run "$CONFIG" "$DATA/monoslam_testseq" "$o"
printf '%-22s %-24s %-24s %-24s %s\n' monoslam_testseq "$(ate "$o/trajectory.txt" "$r")" \
  "$(ate "$o/trajectory_smoothed.txt" "$r")" "$(ate "$o/trajectory_refined.txt" "$r")" "$(timing "$o.log")"
# Hold-out seeds, static world.
rows=$(mktemp); trap 'rm -f "$rows"' EXIT
for s in "${SEEDS[@]}"; do
  d="$OUT/holdout-static-$s"
  [ -f "$d/rgb.txt" ] || "$BUILD/bin/imm-render" "${STATIC_SCENARIO:-ini/scenarios/holdout/pause-pan-movers.ini}" "$d" --seed "$s" \
    --set objects.enabled=false > /dev/null
  o="$OUT/out-holdout-static-$s"
  run "$CONFIG" "$d" "$o" || true
  a=$(ate "$o/trajectory.txt" "$d/groundtruth.txt"); b=$(ate "$o/trajectory_smoothed.txt" "$d/groundtruth.txt")
  c=$(ate "$o/trajectory_refined.txt" "$d/groundtruth.txt")
  printf '%-22s %-24s %-24s %-24s %s\n' "holdout seed $s" "$a" "$b" "$c" "$(timing "$o.log")"
  echo "${a% *} ${b% *} ${c% *}" >> "$rows"
done
awk '{ a[NR] = $1; b[NR] = $2; c[NR] = $3; sa += $1; sb += $2; sc += $3; if ($2 < $1) w++ }
  END { n = NR; printf "hold-out mean %% of path over %d seeds: filter %.3f, smoothed %.3f, refined %.3f; smoothed better than the filter on %d\n", n, sa / n, sb / n, sc / n, w }' "$rows"
