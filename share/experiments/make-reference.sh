#!/usr/bin/env bash
# A reference trajectory for a real sequence that has no usable ground truth: a COLMAP reconstruction of
# its images (Debian's colmap: SIFT features, sequential matching, incremental mapping and bundle
# adjustment), written as TUM (T_world_camera, the sequence's timestamps) for slam-eval.
# Usage: share/experiments/make-reference.sh DATASET_FOLDER [--out DIR] [--camera-model NAME --camera-params LIST]
#        (default --out /tmp/make-reference; relative folders from the repository root;
#        share/experiments/args.sh)
# DATASET_FOLDER: rgb.txt + images (../shared/data/README.md). --camera-model/--camera-params: COLMAP's
# (default from calib.txt, held fixed: pinhole -> PINHOLE fx,fy,cx,cy; davison -> OPENCV_FISHEYE
# fx,fy,cx,cy,k1..k4, k fitted by least squares to Davison's r_u = r_d / sqrt(1 - 2 kd1 r_d^2) over the
# image radius (share/experiments/davison-fisheye-fit.py; residual 0.0003 px for monoslam_testseq).
# COLMAP's RADIAL cannot follow that model to a wide lens's corners, and a refined focal length drifts
# on a slow start.) Writes OUT/reference.txt, OUT/reference_stats.txt (registered images, points, mean
# reprojection error) and keeps COLMAP's database and model in OUT. Needs: apt-get install colmap.
# Nothing is written into the repository.
# Environment: THREADS (COLMAP's threads, default 2), OVERLAP (sequential matching, default 15),
#   REFINE=1 (refine focal length and distortion in bundle adjustment, default 0),
#   MAPPER_ARGS (extra `colmap mapper` options, e.g. "--Mapper.multiple_models 0"),
#   SKIP_MATCHING=1 (reuse OUT/database.db: mapping only).
set -euo pipefail
cd "$(dirname "$0")/../.."
source share/experiments/args.sh
ARGS_COMMON="--out"
ARGS_NEEDS_BUILD=0
ARGS_NPOS=1 ARGS_POS_NAMES=DATASET_FOLDER
CAM_MODEL=''; CAM_PARAMS=''
args_option --camera-model CAM_MODEL
args_option --camera-params CAM_PARAMS
args_parse "$@"
[ -f "${POS[0]}/rgb.txt" ] || args_die "dataset folder '${POS[0]}' has no rgb.txt"
SEQ=$(cd "${POS[0]}" && pwd); mkdir -p "$OUT"; OUT=$(cd "$OUT" && pwd)
read -r MODEL W H FX FY CX CY K1 < <(grep -v '^#' "$SEQ/calib.txt" | head -1) || true
REFINE=${REFINE:-0}
if [[ -n "$CAM_MODEL" && -z "$CAM_PARAMS" ]]; then
  args_die "--camera-model $CAM_MODEL needs --camera-params"
fi
if [[ -z "$CAM_MODEL" ]]; then
  case "$MODEL" in
    pinhole) CAM_MODEL=PINHOLE; CAM_PARAMS="$FX,$FY,$CX,$CY" ;;
    davison) CAM_MODEL=OPENCV_FISHEYE
             CAM_PARAMS="$FX,$FY,$CX,$CY,$(python3 share/experiments/davison-fisheye-fit.py "$W" "$H" "$FX" "$CX" "$CY" "$K1")" ;;
    *) args_die "calib model '$MODEL' of $SEQ/calib.txt needs --camera-model and --camera-params" ;;
  esac
fi
read -r -a MAPPER_EXTRA <<< "${MAPPER_ARGS:-}"
# Images listed in rgb.txt, in order (COLMAP reads a folder: link them under their own names).
mkdir -p "$OUT/images"
grep -v '^#' "$SEQ/rgb.txt" | while read -r ts f; do ln -sf "$SEQ/$f" "$OUT/images/$(basename "$f")"; done
THREADS=${THREADS:-2}
if [[ "${SKIP_MATCHING:-0}" != 1 ]]; then
rm -f "$OUT/database.db"
colmap feature_extractor --database_path "$OUT/database.db" --image_path "$OUT/images" \
  --ImageReader.single_camera 1 --ImageReader.camera_model "$CAM_MODEL" --ImageReader.camera_params "$CAM_PARAMS" \
  --SiftExtraction.use_gpu 0 --SiftExtraction.num_threads "$THREADS" --SiftExtraction.max_num_features 4096 > "$OUT/colmap.log" 2>&1
colmap sequential_matcher --database_path "$OUT/database.db" --SiftMatching.use_gpu 0 \
  --SiftMatching.num_threads "$THREADS" --SequentialMatching.overlap "${OVERLAP:-15}" --SequentialMatching.loop_detection 0 >> "$OUT/colmap.log" 2>&1
fi
rm -rf "$OUT/sparse"; mkdir -p "$OUT/sparse"
colmap mapper --database_path "$OUT/database.db" --image_path "$OUT/images" --output_path "$OUT/sparse" \
  --Mapper.num_threads "$THREADS" --Mapper.ba_refine_focal_length "$REFINE" --Mapper.ba_refine_extra_params "$REFINE" \
  --Mapper.ba_refine_principal_point 0 --Mapper.multiple_models 1 --Mapper.init_min_tri_angle 4 \
  "${MAPPER_EXTRA[@]}" >> "$OUT/colmap.log" 2>&1
# The largest model (a slow start can make the mapper begin more than one).
MODEL_DIR=""; BEST=0
for d in "$OUT"/sparse/*/; do
  colmap model_converter --input_path "$d" --output_path "$d" --output_type TXT >> "$OUT/colmap.log" 2>&1
  n=$(grep -v '^#' "$d/images.txt" | grep -c . || true)
  if (( n > BEST )); then BEST=$n; MODEL_DIR=${d%/}; fi
done
[[ -n "$MODEL_DIR" ]] || { echo "make-reference: COLMAP made no model (see $OUT/colmap.log)" >&2; exit 1; }
python3 - "$SEQ/rgb.txt" "$MODEL_DIR" "$OUT" <<'PY'
import sys, math
rgb, model, out = sys.argv[1:4]
stamp = {}
for line in open(rgb):
    if line.startswith('#') or not line.strip(): continue
    ts, f = line.split()[:2]
    stamp[f.split('/')[-1]] = ts
poses = []
lines = [l for l in open(model + '/images.txt') if not l.startswith('#')]
for i in range(0, len(lines), 2):
    p = lines[i].split()
    if len(p) < 10: continue
    qw, qx, qy, qz, tx, ty, tz = map(float, p[1:8])
    name = p[9]
    # COLMAP stores camera-from-world (R_CW, t_CW); TUM wants world-from-camera: R_WC = R_CW^T, t = -R_CW^T t_CW.
    R = [[1-2*(qy*qy+qz*qz), 2*(qx*qy-qz*qw), 2*(qx*qz+qy*qw)],
         [2*(qx*qy+qz*qw), 1-2*(qx*qx+qz*qz), 2*(qy*qz-qx*qw)],
         [2*(qx*qz-qy*qw), 2*(qy*qz+qx*qw), 1-2*(qx*qx+qy*qy)]]
    c = [-(R[0][k]*tx + R[1][k]*ty + R[2][k]*tz) for k in range(3)]
    poses.append((float(stamp[name]), c, (-qx, -qy, -qz, qw)))  # conjugate quaternion = R^T
poses.sort()
with open(out + '/reference.txt', 'w') as f:
    f.write('# timestamp tx ty tz qx qy qz qw (COLMAP reconstruction, T_world_camera)\n')
    for ts, c, q in poses:
        f.write('%.6f %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n' % (ts, c[0], c[1], c[2], q[0], q[1], q[2], q[3]))
npts = sum(1 for l in open(model + '/points3D.txt') if not l.startswith('#'))
errs = [float(l.split()[7]) for l in open(model + '/points3D.txt') if not l.startswith('#')]
cams = [l.strip() for l in open(model + '/cameras.txt') if not l.startswith('#')]
total = len(stamp)
with open(out + '/reference_stats.txt', 'w') as f:
    f.write('registered %d of %d images; %d points; mean reprojection error %.3f px; camera %s\n'
            % (len(poses), total, npts, sum(errs) / max(1, len(errs)), cams[0] if cams else '?'))
print(open(out + '/reference_stats.txt').read().strip())
PY
