#!/usr/bin/env bash
# Real video with moving objects (doc/shadow.md, "Real video with pasted moving objects"): pastes
# objects cut from one real sequence into another (imm-composite; masks as truth) and runs the full
# system (ini/imm7-shadow.ini), the IMM without shadow filter (ini/imm7.ini) and the single model
# (ini/single.ini) on the composites. Prints per composite and config: frames tracked and the ATE
# against the AprilTag ground truth (visp_rbt) or, for monoslam_testseq (no ground truth), the
# deviation from the full system's run on the clean sequence (both as % of path after Sim(3)); and
# the full system's static/dynamic decisions scored against the masks; and the paper's Fig. 5(a)
# baseline, the IMM with the objects' features disabled ([input] exclusion_masks = the masks).
# Usage: share/experiments/composite-real.sh [--build DIR] [--out DIR] [--data DIR]
#        (defaults: build, /tmp/composite-real, $IMMSLAM_SHARED_DATA_DIR or ../shared/data; share/experiments/args.sh)
set -euo pipefail
cd "$(dirname "$0")/../.."
source share/experiments/args.sh
ARGS_COMMON="--build --out --data"
args_parse "$@"
for d in monoslam_testseq visp_rbt; do
  [ -d "$DATA/$d" ] || { echo "composite-real.sh: $DATA/$d not found (skipped)"; exit 0; }
done
mkdir -p "$OUT"
BIN=$BUILD/bin
VISP_OBJ=$DATA/visp_rbt/rgb/color_image_0050.png  # objects for monoslam_testseq: parts of a visp_rbt frame
TS_OBJ=$DATA/monoslam_testseq/rgb/000500.png       # objects for visp_rbt: parts of a monoslam_testseq frame

composite() {  # NAME SOURCE OBJECT-IMAGE [object options...]
  local name=$1 src=$2 img=$3
  shift 3
  printf '%-10s ' "$name"
  "$BIN/imm-composite" "$src" "$OUT/$name" --object "$img" "$@" | grep -o 'objects in.*'
}
# monoslam_testseq (320x240 grey, hand-held office):
#  ts-small: three passes of a textured box (11 % of the image on average), one approaching;
#  ts-large: two passes of a large cut-out of a desk scene (20 % on average, up to 43 %).
composite ts-small "$DATA/monoslam_testseq" "$VISP_OBJ" --crop 180,275,145,140 --scale 0.8 \
    --path -60,140,380,110 --span 150,330 --wave 15,45 \
  --object "$VISP_OBJ" --crop 180,275,145,140 --scale 0.7,1.2 --path 380,60,-60,170 --span 480,640 --wave 10,60 \
  --object "$VISP_OBJ" --crop 420,310,160,110 --scale 0.9 --path 160,300,170,-60 --span 780,900 --wave 20,40
composite ts-large "$DATA/monoslam_testseq" "$VISP_OBJ" --crop 170,140,400,280 --scale 0.45 \
    --path -100,120,420,120 --span 100,400 --wave 30,60 \
  --object "$VISP_OBJ" --crop 170,140,400,280 --scale 0.5,0.7 --path 420,100,-100,140 --span 600,900 --wave 30,60
# visp_rbt (640x480 colour, AprilTag ground truth): four paths of a cluttered desk cut from a
# monoslam_testseq frame.
composite vi-1 "$DATA/visp_rbt" "$TS_OBJ" --crop 30,60,220,150 --scale 1.1 --path -140,300,780,220 --span 12,92 --wave 25,40
composite vi-2 "$DATA/visp_rbt" "$TS_OBJ" --crop 30,60,220,150 --scale 1.5 --path 780,100,-140,380 --span 5,98 --wave 40,25
composite vi-3 "$DATA/visp_rbt" "$TS_OBJ" --crop 100,20,200,200 --scale 0.8,1.6 --path 320,-100,300,560 --span 20,98 --wave 60,30
composite vi-4 "$DATA/visp_rbt" "$TS_OBJ" --crop 0,0,320,240 --scale 1.0 --path -160,240,800,240 --span 0,98 --wave 30,50

run() {  # CONFIG INPUT OUT [extra args...]
  local cfg=$1 in=$2 o=$3
  shift 3
  "$BIN/imm-monoslam" "$cfg" "$in" --out "$o" --no-gui --quiet "$@" > "$o.log" 2>&1 || true
}
ate() { "$BIN/slam-eval" ate "$1" "$2" 2>/dev/null | awk -F: '/ATE \/ path/ { gsub(/[ %]/, "", $2); print $2 }'; }
frames() { awk 'END { print NR }' "$1/trajectory.txt"; }
rates() {
  "$BIN/slam-eval" classification "$1/classifications.csv" --masks "$2" 2>&1 |
    awk '/moving->static rate/ { m = $NF } /static->dynamic rate/ { s = $NF } END { print "moving->static " m, " static->dynamic " s }' | tr -d '()'
}

run ini/imm7-shadow.ini "$DATA/monoslam_testseq" "$OUT/ts-clean-full" --set output.overlays=true --set output.overlay_every_n=10
run ini/imm7-shadow.ini "$DATA/visp_rbt" "$OUT/vi-clean-full"
printf '\n%-10s %-12s %-7s %-9s %s\n' sequence config frames "% path" "(testseq: deviation from the clean full run; visp: ATE)"
printf '%-10s %-12s %-7s %s\n' ts-clean imm7-shadow "$(frames "$OUT/ts-clean-full")" "$(ate "$OUT/ts-clean-full/trajectory.txt" "$OUT/ts-clean-full/trajectory.txt")"
printf '%-10s %-12s %-7s %s\n' vi-clean imm7-shadow "$(frames "$OUT/vi-clean-full")" "$(ate "$OUT/vi-clean-full/trajectory.txt" "$DATA/visp_rbt/groundtruth.txt")"
for seq in ts-small ts-large vi-1 vi-2 vi-3 vi-4; do
  case $seq in
    ts-*) ref=$OUT/ts-clean-full/trajectory.txt ;;
    *) ref=$DATA/visp_rbt/groundtruth.txt ;;
  esac
  for cfg in imm7-shadow imm7 single; do
    extra=()
    [ "$cfg" = imm7-shadow ] && extra=(--set output.overlays=true --set output.overlay_every_n=5)
    run "ini/$cfg.ini" "$OUT/$seq" "$OUT/$seq-$cfg" "${extra[@]}"
    printf '%-10s %-12s %-7s %s\n' "$seq" "$cfg" "$(frames "$OUT/$seq-$cfg")" "$(ate "$OUT/$seq-$cfg/trajectory.txt" "$ref")"
  done
  # The paper's Fig. 5(a): the IMM with the objects' features disabled ([input] exclusion_masks).
  run ini/imm7.ini "$OUT/$seq" "$OUT/$seq-imm7-disabled" --set "input.exclusion_masks=$OUT/$seq"
  printf '%-10s %-12s %-7s %s\n' "$seq" imm7-disabled "$(frames "$OUT/$seq-imm7-disabled")" \
    "$(ate "$OUT/$seq-imm7-disabled/trajectory.txt" "$ref")"
  printf '%-10s %s\n' "$seq" "full system decisions: $(rates "$OUT/$seq-imm7-shadow" "$OUT/$seq")"
done

# Single composites are fragile: five small variations of ts-large (object scale, wave amplitude and
# period) and of vi-4 (scale, wave amplitude), the full system and the IMM without shadow filter
# (the variations of ShadowSystem.RealVideoWithPastedMovingObjects).
echo
echo "== variations: ts-large (deviation) and vi-4 (ATE), % of path =="
for v in "0.45 30 60" "0.44 30 60" "0.46 30 60" "0.45 28 60" "0.45 30 56"; do
  set -- $v
  "$BIN/imm-composite" "$DATA/monoslam_testseq" "$OUT/var-ts" --object "$VISP_OBJ" --crop 170,140,400,280 --scale "$1" \
      --path -100,120,420,120 --span 100,400 --wave "$2,$3" \
    --object "$VISP_OBJ" --crop 170,140,400,280 --scale 0.5,0.7 --path 420,100,-100,140 --span 600,900 --wave "$2,$3" > /dev/null
  run ini/imm7-shadow.ini "$OUT/var-ts" "$OUT/var-ts-full"
  run ini/imm7.ini "$OUT/var-ts" "$OUT/var-ts-imm7"
  printf 'ts-large scale %s wave %s,%s: full %s  imm7 %s  (%s)\n' "$1" "$2" "$3" \
    "$(ate "$OUT/var-ts-full/trajectory.txt" "$OUT/ts-clean-full/trajectory.txt")" \
    "$(ate "$OUT/var-ts-imm7/trajectory.txt" "$OUT/ts-clean-full/trajectory.txt")" "$(rates "$OUT/var-ts-full" "$OUT/var-ts")"
done
for v in "1.0 30" "0.98 30" "1.02 30" "1.0 29" "1.0 31"; do
  set -- $v
  "$BIN/imm-composite" "$DATA/visp_rbt" "$OUT/var-vi" --object "$TS_OBJ" --crop 0,0,320,240 --scale "$1" \
    --path -160,240,800,240 --span 0,98 --wave "$2,50" > /dev/null
  run ini/imm7-shadow.ini "$OUT/var-vi" "$OUT/var-vi-full"
  run ini/imm7.ini "$OUT/var-vi" "$OUT/var-vi-imm7"
  printf 'vi-4 scale %s wave %s,50: full %s  imm7 %s  (%s)\n' "$1" "$2" \
    "$(ate "$OUT/var-vi-full/trajectory.txt" "$DATA/visp_rbt/groundtruth.txt")" \
    "$(ate "$OUT/var-vi-imm7/trajectory.txt" "$DATA/visp_rbt/groundtruth.txt")" "$(rates "$OUT/var-vi-full" "$OUT/var-vi")"
done
