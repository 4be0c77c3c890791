# The experiment scripts' common options (sourced, not run). A script sources it from the repository
# root, sets its defaults, declares its own options and parses:
#   source share/experiments/args.sh
#   OUT=/tmp/moving-ate; SEEDS=(7 11 23 42 101)     # defaults that differ from the ones below
#   args_option --opencv-doc DOC                    # a script's own option taking a value: sets DOC
#   ARGS_NPOS=1 ARGS_POS_NAMES=SCENARIO.ini         # positional arguments it takes (default 0), in POS
#   ARGS_NEEDS_BUILD=0                              # it runs no binary of the build
#   ARGS_COMMON="--build --out --data"              # the common options it takes (default all four)
#   args_parse "$@"
# Common options and their defaults:
#   --build DIR   the build folder with bin/ (default build)
#   --out DIR     where renders and runs go (default /tmp/<script name>)
#   --seeds LIST  render seeds: a range 101-140, a list 7,11,23, or both 1-5,9 (default: the script's)
#   --data DIR    the shared data sets (default $IMMSLAM_SHARED_DATA_DIR, else ../shared/data)
#   -h, --help    the script's header comment
# Relative folders are relative to the repository root (the scripts run from there).
# Bad input (an unknown option, a missing value, a malformed seed list, an extra argument) stops the
# script with a message that names it and exit status 2.

ARGS_SCRIPT=$(basename "$0")
BUILD=build
OUT=/tmp/${ARGS_SCRIPT%.sh}
DATA=${IMMSLAM_SHARED_DATA_DIR:-../shared/data}
SEEDS=()
ARGS_NPOS=0
ARGS_POS_NAMES=
ARGS_NEEDS_BUILD=1
ARGS_COMMON="--build --out --seeds --data"
POS=()
declare -A ARGS_EXTRA=()

args_die() {
  echo "$ARGS_SCRIPT: $*; see $ARGS_SCRIPT --help" >&2
  exit 2
}

# The comment block after the '#!' line, without the leading '# '.
args_help() {
  awk 'NR == 1 && /^#!/ { next } /^#/ { sub(/^# ?/, ""); print; next } { exit }' "$0"
}

# args_option --NAME VAR: the script takes --NAME VALUE and reads it from VAR.
args_option() {
  ARGS_EXTRA[$1]=$2
}

# Expands "101-140", "7,11,23" or "1-5,9" into SEEDS; non-negative integers only.
args_seeds() {
  local list=$1 item items
  SEEDS=()
  [ -n "$list" ] || args_die "--seeds needs a value such as 101-140 or 7,11,23"
  IFS=, read -r -a items <<< "$list"
  for item in "${items[@]}"; do
    if [[ $item =~ ^[0-9]+$ ]]; then
      SEEDS+=("$item")
    elif [[ $item =~ ^([0-9]+)-([0-9]+)$ ]] && (( BASH_REMATCH[1] <= BASH_REMATCH[2] )); then
      mapfile -t -O "${#SEEDS[@]}" SEEDS < <(seq "${BASH_REMATCH[1]}" "${BASH_REMATCH[2]}")
    else
      args_die "--seeds: '$item' in '$list' is neither a seed nor a range FIRST-LAST (FIRST <= LAST)"
    fi
  done
}

args_parse() {
  local opt value
  while [ $# -gt 0 ]; do
    opt=$1
    if [[ $opt == --*=* ]]; then  # --name=value as well as --name value
      set -- "${opt%%=*}" "${opt#*=}" "${@:2}"
      opt=$1
    fi
    case $opt in
      -h | --help) args_help; exit 0 ;;
      --build | --out | --data | --seeds)
        [[ " $ARGS_COMMON " == *" $opt "* ]] || args_die "option '$opt' does not apply to this script" ;;
      -*) [ -n "${ARGS_EXTRA[$opt]+x}" ] || args_die "unknown option '$opt'" ;;
      *)
        [ ${#POS[@]} -lt "$ARGS_NPOS" ] ||
          args_die "unexpected argument '$opt' (it takes ${ARGS_POS_NAMES:-no arguments} besides the options $ARGS_COMMON)"
        POS+=("$opt")
        shift
        continue ;;
    esac
    [ $# -ge 2 ] && [[ $2 != -* ]] || args_die "option '$opt' needs a value"
    value=$2
    shift 2
    case $opt in
      --build) BUILD=$value ;;
      --out) OUT=$value ;;
      --data) DATA=$value ;;
      --seeds) args_seeds "$value" ;;
      *) printf -v "${ARGS_EXTRA[$opt]}" '%s' "$value" ;;
    esac
  done
  [ ${#POS[@]} -eq "$ARGS_NPOS" ] || args_die "missing argument: it takes $ARGS_POS_NAMES besides the options"
  if [ "$ARGS_NEEDS_BUILD" = 1 ] && [ ! -x "$BUILD/bin/imm-monoslam" ]; then
    args_die "--build '$BUILD' has no bin/imm-monoslam (build first, or name the build folder)"
  fi
}
