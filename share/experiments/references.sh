# The reference trajectories the experiment scripts score real sequences against (sourced, not run;
# after share/experiments/args.sh, which sets BUILD and DATA).
#   testseq_reference OUT_DIR   prints the path of monoslam_testseq's reference: TESTSEQ_REF when set
#                               (e.g. a COLMAP reconstruction of share/experiments/make-reference.sh),
#                               else the bundle adjustment of an independent run's matches
#                               (ini/single.ini, its trajectory_refined.txt), made once under OUT_DIR.
testseq_reference() {
  if [ -n "${TESTSEQ_REF:-}" ]; then
    echo "$TESTSEQ_REF"
    return
  fi
  local ref="$1/testseq_single_reference"
  [ -s "$ref/trajectory_refined.txt" ] ||
    "$BUILD/bin/imm-monoslam" ini/single.ini "$DATA/monoslam_testseq" --out "$ref" --no-gui --quiet \
      --set output.scene=false --set output.refine_trajectory=true > "$ref.log" 2>&1
  echo "$ref/trajectory_refined.txt"
}
