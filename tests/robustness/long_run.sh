#!/usr/bin/env bash
# Long run of issue 8 (reported, not a timed test): 10 020 rendered frames (long_run.ini) through
# imm-monoslam with ini/imm7.ini; samples the resident memory (VmRSS of /proc/PID/status) every
# INTERVAL seconds into OUT/rss.csv and reports frames, wall time, peak RSS (/usr/bin/time -v) and
# RSS over time. Usage: tests/robustness/long_run.sh [BUILD_DIR] [OUT] [CONFIG]
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
BUILD=${1:-$ROOT/build}
OUT=${2:-$BUILD/test-out/long_run}
CONFIG=${3:-$ROOT/ini/imm7.ini}
INTERVAL=${INTERVAL:-5}
rm -rf "$OUT"; mkdir -p "$OUT"
TIME=(); [ -x /usr/bin/time ] && TIME=(/usr/bin/time -v -o "$OUT/time.txt")
"${TIME[@]}" "$BUILD/bin/imm-monoslam" "$CONFIG" --set "input.scenario=$HERE/long_run.ini" \
  --no-gui --quiet --out "$OUT/out" > "$OUT/stdout.txt" 2> "$OUT/stderr.txt" &
WRAP=$!
sleep 1
PID=$(pgrep -P "$WRAP" imm-monoslam || echo "$WRAP")
echo "elapsed_s,frames,vmrss_kb,vmhwm_kb" > "$OUT/rss.csv"
T0=$(date +%s)
while kill -0 "$PID" 2> /dev/null; do
  rss=$(awk '/^VmRSS/{print $2}' "/proc/$PID/status" 2> /dev/null || true)
  hwm=$(awk '/^VmHWM/{print $2}' "/proc/$PID/status" 2> /dev/null || true)
  frames=$({ wc -l < "$OUT/out/trajectory.txt"; } 2> /dev/null || echo 0)
  [ -n "$rss" ] && echo "$(( $(date +%s) - T0 )),$frames,$rss,$hwm" >> "$OUT/rss.csv"
  sleep "$INTERVAL"
done
wait "$WRAP"; STATUS=$?
echo "exit status $STATUS"
tail -n 1 "$OUT/stdout.txt"
[ -f "$OUT/time.txt" ] && grep -E "Maximum resident|Elapsed \(wall|User time|System time" "$OUT/time.txt"
python3 - "$OUT/rss.csv" <<'PY' || true
import csv, sys
rows = [r for r in csv.DictReader(open(sys.argv[1])) if int(r["frames"]) > 0]
if rows:
    pick = [rows[int(i * (len(rows) - 1) / 10)] for i in range(11)]
    print("RSS over time (frames: MiB):", ", ".join(f'{r["frames"]}: {int(r["vmrss_kb"]) / 1024:.0f}' for r in pick))
    half = [r for r in rows if int(r["frames"]) >= int(rows[-1]["frames"]) // 2]
    print(f'RSS growth over the second half: {(int(half[-1]["vmrss_kb"]) - int(half[0]["vmrss_kb"])) / 1024:.1f} MiB '
          f'over {int(half[-1]["frames"]) - int(half[0]["frames"])} frames')
PY
exit $STATUS
