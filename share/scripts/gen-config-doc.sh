#!/usr/bin/env bash
# Regenerates doc/configuration.md from the options classes themselves (imm-monoslam --print-config):
# every key of every section, its default and its comment.
set -euo pipefail
cd "$(dirname "$0")/../.."
BIN=${1:-build/bin/imm-monoslam}
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
printf '[input]\n' > "$TMP/empty.ini"
{
  echo "# Configuration reference"
  echo
  echo "Generated from the options classes by \`share/scripts/gen-config-doc.sh\` (\`imm-monoslam CONFIG --print-config\`"
  echo "prints the same for any config, with its values). Every key is optional; unknown keys and sections are"
  echo "errors that name them (with the closest known key). Override any key on the command line with"
  echo "\`--set SECTION.KEY=VALUE\`. Noise values are in pixels (the dimensionless formulation, doc/conventions.md)."
  echo
  echo "The camera is not a section of the shipped configs: it comes from the input (calib.txt, the rawlog's"
  echo "\`cameraParams\`) or \`--calib FILE\`. A \`[camera]\` section (MRPT \`[CAMERA_PARAMS]\` keys: \`resolution\`, \`cx\`,"
  echo "\`cy\`, \`fx\`, \`fy\`, \`dist\`, \`distortion_model\` = \`none\`, \`plumb_bob\` or \`kannala_brandt\`; or"
  echo "\`model = pinhole|opencv|davison|fisheye\` with \`kd1\` (davison) or \`dist\` (fisheye: \`[k1 k2 k3 k4]\`); or"
  echo "\`calib_file = path\`) is used for live cameras. Precedence: \`--calib\` > \`[camera]\` > the input's own."
  echo
  echo "The defaults are the recommended configuration (\`ini/imm7-shadow.ini\` only names its defining keys)."
  echo "A config written for an older version that holds a removed or moved key stops with an error naming"
  echo "the key and what replaced it (for example \`[shadow] min_ncc: moved to [search] min_ncc\`). The keys are those a"
  echo "user turns; the algorithms' tuning internals (RANSAC probabilities, deletion rule, relocalisation counts,"
  echo "the shadow filter's decision rule, ...) are named constants in the code (doc/estimator.md, doc/shadow.md):"
  echo "a config that sets one stops with \`removed: internal constant (VALUE; DOC)\`."
  "$BIN" "$TMP/empty.ini" --print-config | awk '
    /^\[/ { sec=$0; gsub(/[\[\]]/, "", sec); printf "\n## [%s]\n\n| key | default | meaning |\n|---|---|---|\n", sec; next }
    /=/ {
      key=$1; line=$0; sub(/^[^=]*=[ ]*/, "", line);
      com=""; if (index(line, "//")) { com=substr(line, index(line, "//")+2); line=substr(line, 1, index(line, "//")-1) }
      gsub(/[ ]+$/, "", line); gsub(/^[ ]+/, "", com); gsub(/\|/, "\\|", com); gsub(/\|/, "\\|", line)
      printf "| `%s` | `%s` | %s |\n", key, line, com
    }'
} > doc/configuration.md
echo "wrote doc/configuration.md"
