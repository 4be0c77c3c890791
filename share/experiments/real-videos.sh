#!/usr/bin/env bash
# Real video of people and of a hand in front of the camera (doc/shadow.md, "Real video of a hand and
# of people"): the two videos of Debian's opencv-doc package that a still camera took of moving people
# (examples/data/vtest.avi, 768x576, 10 Hz) and of a hand moving a box (opencv4/html/box.mp4.gz,
# 640x480, 30 Hz), each as it is (camera at rest) and turned by imm-rotate into a rotating camera's
# video (pan/tilt/roll 3/2/1.5 degrees, the defaults). Truth: the camera does not translate, its
# rotation is known, and masks/ mark what moves. Per run: rotation RMSE (no alignment), the largest
# camera displacement relative to the median distance of the map's features (the estimate should not
# translate: scale-free), motion segmentation accuracy against motion_labels.txt, and the shadow
# filter's decisions against the masks. With DATA/monoslam_testseq, also the hand and the box
# of box.mp4 pasted into that real hand-held video (a real hand in front of a real moving camera).
# The calibrations are guesses (the videos come without one): f = 560 px for box.mp4 (a 60-degree
# webcam), f = 700 px for vtest.avi; imm-rotate uses the same model to make the rotation, so the
# rotating versions are consistent with them up to the real lenses' distortion.
# Last, cup.mp4 (opencv4/html/cup.mp4.gz): a hand holding a cup before a bare wall, the camera hand-held
# and turning about 1 degree (its wall marks shift by <= 10 px): the largest rotation of each config's
# estimate, and the shadow filter's decisions (no masks: the video is not still). Not solved.
# Usage: share/experiments/real-videos.sh [--build DIR] [--out DIR] [--data DIR] [--opencv-doc DIR]
#        (defaults: build, /tmp/real-videos, $IMMSLAM_SHARED_DATA_DIR or ../shared/data, /usr/share/doc/opencv-doc;
#        apt-get install opencv-doc; share/experiments/args.sh)
#        EXTRA_SET="--set system.watch_features=0" adds options to every imm-monoslam run.
set -euo pipefail
cd "$(dirname "$0")/../.."
source share/experiments/args.sh
ARGS_COMMON="--build --out --data"
DOC=/usr/share/doc/opencv-doc
args_option --opencv-doc DOC
args_parse "$@"
read -r -a EXTRA <<< "${EXTRA_SET:-}"
VTEST="$DOC/examples/data/vtest.avi"
BOXGZ="$DOC/opencv4/html/box.mp4.gz"
for f in "$VTEST" "$BOXGZ"; do
  [ -f "$f" ] || { echo "real-videos: $f not found (apt-get install opencv-doc, or give its folder: --opencv-doc)" >&2; exit 1; }
done
mkdir -p "$OUT"
[ -f "$OUT/box.mp4" ] || gzip -dc "$BOXGZ" > "$OUT/box.mp4"
printf '# model width height fx fy cx cy  (a guess: the video has no calibration)\npinhole 640 480 560 560 319.5 239.5\n' > "$OUT/box_calib.txt"
printf '# model width height fx fy cx cy  (a guess: the video has no calibration)\npinhole 768 576 700 700 383.5 287.5\n' > "$OUT/vtest_calib.txt"
make_seq() {  # NAME VIDEO CALIB ROTATE SIZE
  [ -f "$OUT/$1/rgb.txt" ] && return 0
  "$BUILD/bin/imm-rotate" "$2" "$OUT/$1" --calib "$3" --rotate "$4" ${5:+--size "$5"} 2> /dev/null | sed 's/^/  /'
}
make_seq box-still "$OUT/box.mp4" "$OUT/box_calib.txt" 0,0,0 640,480
make_seq box-rotating "$OUT/box.mp4" "$OUT/box_calib.txt" 3,2,1.5
make_seq vtest-still "$VTEST" "$OUT/vtest_calib.txt" 0,0,0 768,576
make_seq vtest-rotating "$VTEST" "$OUT/vtest_calib.txt" 3,2,1.5

field() { grep -m1 "$1" | sed 's/.*: *//' | awk '{print $1}'; }
printf '%-15s %-12s %-9s %-10s %-9s %-9s %-7s %-14s %s\n' sequence config rot_deg transl/d segment% dynamic static \
  'moving->static' 'static->dynamic'
for seq in box-still box-rotating vtest-still vtest-rotating; do
  for cfg in imm7-shadow imm7 single single-shadow; do
    o="$OUT/out-$seq-$cfg"
    "$BUILD/bin/imm-monoslam" "ini/$cfg.ini" "$OUT/$seq" --out "$o" --no-gui --quiet "${EXTRA[@]}" > /dev/null
    rot=$("$BUILD/bin/slam-eval" ate "$o/trajectory.txt" "$OUT/$seq/groundtruth.txt" --no-align | field 'rotation RMSE')
    # Largest displacement of the camera over the median distance of the map's features from the start.
    m=$(awk '$0 !~ /^#/ && NF == 8 { d = sqrt($2*$2 + $3*$3 + $4*$4); if (d > m) m = d } END { print m + 0 }' "$o/trajectory.txt")
    med=$(awk -F, 'FNR > 1 { print sqrt($2*$2 + $3*$3 + $4*$4) }' "$o/map.csv" | sort -g |
          awk '{ v[NR] = $1 } END { print (NR ? v[int((NR + 1) / 2)] : 0) }')
    disp=$(awk -v m="$m" -v d="$med" 'BEGIN { printf (d > 0 ? "%.3f" : "-"), m / d }')
    seg=$("$BUILD/bin/slam-eval" segmentation "$o/model_probabilities.csv" "$OUT/$seq/motion_labels.txt" |
          grep -o 'accuracy [0-9.]*' | awk '{print $2}')
    dyn=- st=- ms=- sd=-
    if [ -s "$o/classifications.csv" ]; then
      dyn=$(awk -F, 'NR > 1 && $3 == "dynamic"' "$o/classifications.csv" | wc -l)
      st=$(awk -F, 'NR > 1 && $3 == "static"' "$o/classifications.csv" | wc -l)
      c=$("$BUILD/bin/slam-eval" classification "$o/classifications.csv" --masks "$OUT/$seq")
      ms=$(echo "$c" | grep -o 'moving->static rate : .*' | sed 's/.*(\(.*\))/\1/')
      sd=$(echo "$c" | grep -o 'static->dynamic rate: .*' | sed 's/.*(\(.*\))/\1/')
    fi
    printf '%-15s %-12s %-9s %-10s %-9s %-9s %-7s %-14s %s\n' "$seq" "$cfg" "$rot" "$disp" "$seg" "$dyn" "$st" "$ms" "$sd"
  done
done

# A real hand in front of a real moving camera: what moves in box.mp4 (cut out by box-still's masks)
# pasted into monoslam_testseq (a hand-held camera) with imm-composite, five placements; deviation of
# each config from the full system's run on the clean sequence (% of path), decisions against the masks.
TS=$DATA/monoslam_testseq
if [ -d "$TS" ]; then
  clean="$OUT/out-testseq-clean"
  "$BUILD/bin/imm-monoslam" ini/imm7-shadow.ini "$TS" --out "$clean" --no-gui --quiet "${EXTRA[@]}" > /dev/null
  printf '\n%-22s %-12s %-12s %-14s %s\n' composite config dev%path 'moving->static' 'static->dynamic'
  for v in "100 554 0.5 0" "300 754 0.45 0" "500 954 0.55 0" "0 354 0.5 100" "600 999 0.5 50"; do
    set -- $v
    seq="ts-hand-$1-$3"
    [ -f "$OUT/$seq/rgb.txt" ] || "$BUILD/bin/imm-composite" "$TS" "$OUT/$seq" --object-video "$OUT/box-still" \
      --scale "$3" --span "$1,$2" --video-start "$4" > /dev/null
    for cfg in imm7-shadow imm7 single; do
      o="$OUT/out-$seq-$cfg"
      "$BUILD/bin/imm-monoslam" "ini/$cfg.ini" "$OUT/$seq" --out "$o" --no-gui --quiet "${EXTRA[@]}" > /dev/null
      dev=$("$BUILD/bin/slam-eval" ate "$o/trajectory.txt" "$clean/trajectory.txt" | field 'ATE / path')
      ms=- sd=-
      if [ -s "$o/classifications.csv" ]; then
        c=$("$BUILD/bin/slam-eval" classification "$o/classifications.csv" --masks "$OUT/$seq")
        ms=$(echo "$c" | grep -o 'moving->static rate : .*' | sed 's/.*(\(.*\))/\1/')
        sd=$(echo "$c" | grep -o 'static->dynamic rate: .*' | sed 's/.*(\(.*\))/\1/')
      fi
      printf '%-22s %-12s %-12s %-14s %s\n' "$seq" "$cfg" "$dev" "$ms" "$sd"
    done
  done
fi

# cup.mp4: a real hand and a real hand-held camera before a bare wall (doc/shadow.md, not solved).
CUPGZ="$DOC/opencv4/html/cup.mp4.gz"
if [ -f "$CUPGZ" ]; then
  [ -f "$OUT/cup.mp4" ] || gzip -dc "$CUPGZ" > "$OUT/cup.mp4"
  printf '\n%-8s %-14s %-16s %-8s %s\n' video config max_rot_deg dynamic static
  for cfg in imm7-shadow imm7 single single-shadow; do
    o="$OUT/out-cup-$cfg"
    "$BUILD/bin/imm-monoslam" "ini/$cfg.ini" "$OUT/cup.mp4" --calib "$OUT/box_calib.txt" --out "$o" --no-gui --quiet \
      "${EXTRA[@]}" > /dev/null
    rot=$(awk '$0 !~ /^#/ && NF == 8 { a = 2 * atan2(sqrt($5*$5 + $6*$6 + $7*$7), $8) * 57.29578; if (a > m) m = a }
               END { printf "%.2f", m }' "$o/trajectory.txt")
    dyn=- st=-
    if [ -s "$o/classifications.csv" ]; then
      dyn=$(awk -F, 'NR > 1 && $3 == "dynamic"' "$o/classifications.csv" | wc -l)
      st=$(awk -F, 'NR > 1 && $3 == "static"' "$o/classifications.csv" | wc -l)
    fi
    printf '%-8s %-14s %-16s %-8s %s\n' cup "$cfg" "$rot" "$dyn" "$st"
  done
fi
