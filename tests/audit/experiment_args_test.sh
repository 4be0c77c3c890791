#!/usr/bin/env bash
# share/experiments/args.sh, the experiment scripts' option parser: defaults, --seeds ranges and lists,
# errors that name the bad option; and every experiment script prints its header with --help and
# stops with status 2 on an unknown option. Run from the repository root (ctest does).
set -uo pipefail
fail=0
check() {  # DESCRIPTION EXPECTED ACTUAL
  if [ "$2" != "$3" ]; then
    echo "FAIL $1: expected '$2', got '$3'"
    fail=1
  else
    echo "ok   $1"
  fi
}
# A stand-in script that sources the helper and prints what it parsed.
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/build/bin" && touch "$tmp/build/bin/imm-monoslam" && chmod +x "$tmp/build/bin/imm-monoslam"
cat > "$tmp/probe.sh" <<EOF
#!/usr/bin/env bash
# The probe's header.
# Second line.
set -euo pipefail
source "$PWD/share/experiments/args.sh"
ARGS_NEEDS_BUILD=\${NEEDS_BUILD:-0}
SEEDS=(7 11)
DOC=none
args_option --opencv-doc DOC
args_parse "\$@"
echo "\$BUILD|\$OUT|\$DATA|\${SEEDS[*]}|\$DOC"
EOF
chmod +x "$tmp/probe.sh"
probe() { env -u IMMSLAM_SHARED_DATA_DIR "$tmp/probe.sh" "$@" 2>&1; }

check defaults "build|/tmp/probe|../shared/data|7 11|none" "$(probe)"
check "data from the environment" "/d" "$(IMMSLAM_SHARED_DATA_DIR=/d "$tmp/probe.sh" | cut -d'|' -f3)"
check options "b|o|d|3|x" "$(probe --build b --out o --data d --seeds 3 --opencv-doc x)"
check "--name=value" "b|o|d|3|x" "$(probe --build=b --out=o --data=d --seeds=3 --opencv-doc=x)"
check "seed range" "101 102 103 104" "$(probe --seeds 101-104 | cut -d'|' -f4)"
check "seed list" "7 11 23" "$(probe --seeds 7,11,23 | cut -d'|' -f4)"
check "range and list" "1 2 3 9" "$(probe --seeds 1-3,9 | cut -d'|' -f4)"
check help "The probe's header.
Second line." "$(probe --help)"
check "unknown option" "probe.sh: unknown option '--sedes'; see probe.sh --help" "$(probe --sedes 3)"
check "missing value" "probe.sh: option '--out' needs a value; see probe.sh --help" "$(probe --out)"
check "an option as value" "probe.sh: option '--out' needs a value; see probe.sh --help" "$(probe --out --seeds 3)"
check "bad seeds" "probe.sh: --seeds: 'x' in '1,x' is neither a seed nor a range FIRST-LAST (FIRST <= LAST); see probe.sh --help" \
  "$(probe --seeds 1,x)"
check "reversed range" 2 "$(probe --seeds 9-3 > /dev/null 2>&1; echo $?)"
check "extra argument" "probe.sh: unexpected argument 'build' (it takes no arguments besides the options --build --out --seeds --data); see probe.sh --help" \
  "$(probe build)"
check "no build" "probe.sh: --build 'nowhere' has no bin/imm-monoslam (build first, or name the build folder); see probe.sh --help" \
  "$(NEEDS_BUILD=1 probe --build nowhere)"
check "a build" "$tmp/build" "$(NEEDS_BUILD=1 probe --build "$tmp/build" | cut -d'|' -f1)"

# Every experiment script: --help prints its header (with a Usage line), an unknown option is status 2
# (args.sh and references.sh are sourced by them, not run).
for s in share/experiments/*.sh; do
  case "$s" in share/experiments/args.sh | share/experiments/references.sh) continue ;; esac
  check "$s --help has a Usage line" 1 "$("$s" --help | grep -c "^Usage: $s")"
  check "$s rejects --bogus" 2 "$("$s" --bogus > /dev/null 2>&1; echo $?)"
done
exit $fail
