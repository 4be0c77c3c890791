#!/usr/bin/env bash
# imm-monoslam — measures speed and memory and regenerates doc/performance.md.
#
#   share/scripts/perf-report.sh [options]
#
# 1. builds Release (benchmarks on, tests off) in its own build folder;
# 2. runs the Google Benchmark programs (tests/benchmarks): bench_filter, bench_frontend and
#    bench_system, each benchmark repeated --reps times; the tables give the medians; bench_shadow
#    (the shadow filter on images) and bench_sim (rendering) are run too, their results kept in OUT;
# 3. memory: runs imm-monoslam on a long rendered run (ini/scenarios/handheld.ini lengthened to
#    --long-frames frames) and samples its VmRSS every 0.5 s; peak RSS from /usr/bin/time;
# 4. optionally (--profile) records a perf profile of the 7-model IMM on monoslam_testseq and on the
#    paper scenario (RelWithDebInfo + -fno-omit-frame-pointer build) and lists the top functions;
# 5. writes doc/performance.md: the tables, the exact commands, the machine (CPU, cores, load average,
#    compiler and flags). The hand-written section between the markers
#    `<!-- manual:begin -->` and `<!-- manual:end -->` of the existing file is kept as it is. The
#    prototype kernels (bench_kernels.cpp, not used by the library) and the wider-SIMD comparison
#    (bench_simd_*) go to OUT/prototypes.md, for doc/experiments/performance.md; the run's date stays
#    in OUT/machine.txt and OUT/prototypes.md.
#
# Options:
#   --build DIR        build folder (default: build-perf)
#   --out DIR          raw results: JSON, CSV, logs (default: BUILD/perf-report)
#   --reps N           repetitions of every benchmark (default 5)
#   --frames N         limit the frames of every bench_system run (default: whole sequences)
#   --long-frames N    frames of the memory run (default 10000, the memory target's; ~4 min)
#   --memory-config C  config of the memory run (default: imm7-shadow if it exists, else imm7)
#   --filter REGEX     only the benchmarks matching REGEX (Google Benchmark --benchmark_filter)
#   --callgrind N      also count instructions (valgrind --tool=callgrind, robust to the machine's
#                      load) of single, imm7 and imm7-shadow over N frames of monoslam_testseq and of
#                      the paper scenario: per-frame instruction counts per function, imm7/single
#                      ratios (~15 min for N = 300)
#   --profile          also profile imm7 with perf (build BUILD-prof: -O3 -g -fno-omit-frame-pointer;
#                      needs `perf`; adds ~15 minutes)
#   --quick            smoke test: 2 repetitions, short benchmarks, 150-frame system runs, 600-frame
#                      memory run
#   --no-build         use the programs already in BUILD/bin
#   --no-doc           do not write doc/performance.md (results stay in OUT)
#   -j N               build jobs (default 2)
# The machine may be shared: the load average is recorded before every part; compare figures of
# the same run, and prefer valgrind --tool=callgrind instruction counts for small differences.
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/../.." && pwd)"
export PERF_REPORT_ARGS="$*"
BUILD="$ROOT/build-perf"
OUT=""
REPS=5
FRAMES=""
LONG_FRAMES=10000
MEM_CONFIG=""
FILTER=""
PROFILE=0
CALLGRIND=0
BUILD_IT=1
WRITE_DOC=1
JOBS=2
QUICK=0
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build) BUILD="$(realpath -m "$2")"; shift 2 ;;
    --out) OUT="$(realpath -m "$2")"; shift 2 ;;
    --reps) REPS="$2"; shift 2 ;;
    --frames) FRAMES="$2"; shift 2 ;;
    --long-frames) LONG_FRAMES="$2"; shift 2 ;;
    --memory-config) MEM_CONFIG="$2"; shift 2 ;;
    --filter) FILTER="$2"; shift 2 ;;
    --profile) PROFILE=1; shift ;;
    --callgrind) CALLGRIND="$2"; shift 2 ;;
    --quick) QUICK=1; REPS=2; FRAMES=150; LONG_FRAMES=600; shift ;;
    --no-build) BUILD_IT=0; shift ;;
    --no-doc) WRITE_DOC=0; shift ;;
    -j) JOBS="$2"; shift 2 ;;
    -h|--help) sed -n '2,40p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "perf-report.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
  esac
done
OUT="${OUT:-$BUILD/perf-report}"
mkdir -p "$OUT"
CMDS="$OUT/commands.txt"
: > "$CMDS"
LOADS="$OUT/loadavg.txt"
: > "$LOADS"
cd "$ROOT"

# Runs a command, logging it (as typed, relative to the project root) for the report.
run() {
  printf '%q ' "$@" | sed "s|$ROOT/||g; s| \$||" >> "$CMDS"
  echo >> "$CMDS"
  "$@"
}
note_load() { echo "$1: $(cut -d' ' -f1-3 /proc/loadavg)" | tee -a "$LOADS" >&2; }

# ---- 1. Build
if [[ $BUILD_IT == 1 ]]; then
  note_load "build"
  run cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DIMMSLAM_BUILD_TESTS=OFF \
    -DIMMSLAM_BUILD_BENCHMARKS=ON > "$OUT/cmake.log"
  SIMD_TARGETS=(bench_simd_sse2)
  grep -qw avx2 /proc/cpuinfo && grep -qw fma /proc/cpuinfo && SIMD_TARGETS+=(bench_simd_avx2)
  run cmake --build "$BUILD" --target bench_filter bench_frontend bench_system bench_shadow bench_sim imm-monoslam \
    "${SIMD_TARGETS[@]}" -j"$JOBS" \
    > "$OUT/build.log" 2>&1 || { tail -30 "$OUT/build.log" >&2; exit 1; }
fi
for p in bench_filter bench_frontend bench_system imm-monoslam; do
  [[ -x "$BUILD/bin/$p" ]] || { echo "perf-report.sh: $BUILD/bin/$p missing (build it, or drop --no-build)" >&2; exit 1; }
done

# ---- Machine
{
  echo "date: $(date -u '+%Y-%m-%d %H:%M UTC')"
  echo "commit: $(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)$(git -C "$ROOT" diff --quiet 2>/dev/null || echo ' (+ uncommitted changes)')"
  echo "cpu: $(lscpu | sed -n 's/^Model name: *//p' | head -1)"
  echo "cores: $(nproc) ($(lscpu | sed -n 's/^Thread(s) per core: *//p') thread(s) per core)"
  echo "memory: $(free -g | awk '/^Mem:/{print $2 " GiB"}')"
  echo "kernel: $(uname -r)"
  echo "compiler: $(sed -n 's/^CMAKE_CXX_COMPILER:[A-Z]*=//p' "$BUILD/CMakeCache.txt") ($("$(sed -n 's/^CMAKE_CXX_COMPILER:[A-Z]*=//p' "$BUILD/CMakeCache.txt")" --version | head -1))"
  echo "build type: $(sed -n 's/^CMAKE_BUILD_TYPE:[A-Z]*=//p' "$BUILD/CMakeCache.txt")"
  echo "flags: $(sed -n 's/^CMAKE_CXX_FLAGS:[A-Z]*=//p' "$BUILD/CMakeCache.txt") $(sed -n 's/^CMAKE_CXX_FLAGS_RELEASE:[A-Z]*=//p' "$BUILD/CMakeCache.txt") -std=c++17 -fPIC -Wall -Wextra -Wpedantic -Wshadow=local -Wnon-virtual-dtor"
  echo "eigen: $(sed -n 's/.*EIGEN_WORLD_VERSION \([0-9]*\).*/\1/p;s/.*EIGEN_MAJOR_VERSION \([0-9]*\).*/\1/p;s/.*EIGEN_MINOR_VERSION \([0-9]*\).*/\1/p' /usr/include/eigen3/Eigen/src/Core/util/Macros.h 2>/dev/null | paste -sd.)"
  echo "google benchmark: $(dpkg-query -W -f='${Version}' libbenchmark-dev 2>/dev/null || echo unknown)"
  echo "reps: $REPS"
} > "$OUT/machine.txt"
cat "$OUT/machine.txt" >&2

BFILTER=()
[[ -n "$FILTER" ]] && BFILTER=(--benchmark_filter="$FILTER")
BMARGS=(--benchmark_repetitions="$REPS" --benchmark_report_aggregates_only=true --benchmark_out_format=json)
[[ $QUICK == 1 ]] && BMARGS+=(--benchmark_min_time=0.1)

# ---- 2. Benchmarks
note_load "bench_filter"
run "$BUILD/bin/bench_filter" "${BMARGS[@]}" ${BFILTER[@]+"${BFILTER[@]}"} --benchmark_out="$OUT/bench_filter.json" \
  | tee "$OUT/bench_filter.txt"
note_load "bench_frontend"
run "$BUILD/bin/bench_frontend" "${BMARGS[@]}" ${BFILTER[@]+"${BFILTER[@]}"} --benchmark_out="$OUT/bench_frontend.json" \
  | tee "$OUT/bench_frontend.txt"
for p in bench_shadow bench_sim; do
  [[ -x "$BUILD/bin/$p" ]] || continue
  note_load "$p"
  run "$BUILD/bin/$p" "${BMARGS[@]}" ${BFILTER[@]+"${BFILTER[@]}"} --benchmark_out="$OUT/$p.json" | tee "$OUT/$p.txt"
done
for v in sse2 avx2; do
  [[ -x "$BUILD/bin/bench_simd_$v" ]] || continue
  [[ $v == avx2 ]] && ! { grep -qw avx2 /proc/cpuinfo && grep -qw fma /proc/cpuinfo; } && continue
  note_load "bench_simd_$v"
  run "$BUILD/bin/bench_simd_$v" "${BMARGS[@]}" --benchmark_out="$OUT/bench_simd_$v.json" | tee "$OUT/bench_simd_$v.txt"
done
note_load "bench_system"
SYSENV=(env IMMSLAM_BENCH_OUT="$OUT/system-runs")
[[ -n "$FRAMES" ]] && SYSENV+=(IMMSLAM_BENCH_MAX_FRAMES="$FRAMES")
run "${SYSENV[@]}" "$BUILD/bin/bench_system" --benchmark_repetitions="$REPS" --benchmark_out_format=json \
  ${BFILTER[@]+"${BFILTER[@]}"} --benchmark_out="$OUT/bench_system.json" | tee "$OUT/bench_system.txt"

# ---- 3. Memory over a long rendered run
if [[ -z "$MEM_CONFIG" ]]; then
  MEM_CONFIG=imm7
  [[ -f "$ROOT/ini/imm7-shadow.ini" ]] && MEM_CONFIG=imm7-shadow
fi
note_load "memory"
SECS=$(( (LONG_FRAMES + 29) / 30 + 1 ))
# The scenario lengthened: one general-motion segment of SECS seconds (same seed, room and path model).
sed -E "s/^segments *=.*/segments = general $SECS/" "$ROOT/ini/scenarios/handheld.ini" > "$OUT/handheld-long.ini"
echo "sed -E 's/^segments *=.*/segments = general $SECS/' ini/scenarios/handheld.ini > ${OUT#$ROOT/}/handheld-long.ini" >> "$CMDS"
MEMDIR="$OUT/memory-run"
rm -rf "$MEMDIR"
mkdir -p "$MEMDIR"
printf '%q ' /usr/bin/time -f %M -o "$MEMDIR/maxrss_kb.txt" "$BUILD/bin/imm-monoslam" "ini/$MEM_CONFIG.ini" --out "$MEMDIR" \
  --no-gui --quiet --set "input.scenario=$OUT/handheld-long.ini" --set output.scene=false \
  --frames "$LONG_FRAMES" | sed "s|$ROOT/||g" >> "$CMDS"
echo " &   # + VmRSS/VmHWM of its PID from /proc/PID/status every 0.5 s" >> "$CMDS"
/usr/bin/time -f %M -o "$MEMDIR/maxrss_kb.txt" "$BUILD/bin/imm-monoslam" "$ROOT/ini/$MEM_CONFIG.ini" \
  --out "$MEMDIR" --no-gui --quiet --set "input.scenario=$OUT/handheld-long.ini" \
  --set output.scene=false --frames "$LONG_FRAMES" > "$MEMDIR/stdout.txt" 2> "$MEMDIR/stderr.txt" &
TPID=$!
APID=""
for _ in $(seq 50); do
  APID="$(pgrep -P "$TPID" || true)"
  [[ -n "$APID" ]] && break
  sleep 0.1
done
echo "seconds,vmrss_kb,vmhwm_kb,frames" > "$OUT/rss.csv"
T0=$(date +%s.%N)
while [[ -n "$APID" ]] && kill -0 "$APID" 2>/dev/null; do
  RSS=$(awk '/^VmRSS:/{print $2}' "/proc/$APID/status" 2>/dev/null || true)
  HWM=$(awk '/^VmHWM:/{print $2}' "/proc/$APID/status" 2>/dev/null || true)
  NF=$(wc -l 2>/dev/null < "$MEMDIR/trajectory.txt" || echo 0)
  [[ -n "$RSS" ]] && echo "$(awk -v a="$(date +%s.%N)" -v b="$T0" 'BEGIN{printf "%.2f", a - b}'),$RSS,$HWM,$NF" >> "$OUT/rss.csv"
  sleep 0.5
done
wait "$TPID" || { echo "perf-report.sh: the memory run failed:" >&2; tail -5 "$MEMDIR/stderr.txt" >&2; exit 1; }
note_load "end of memory run"

# ---- 4. Profiles (optional)
if [[ $PROFILE == 1 ]]; then
  PBUILD="$BUILD-prof"
  note_load "profile build"
  run cmake -S "$ROOT" -B "$PBUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DIMMSLAM_BUILD_TESTS=OFF \
    -DIMMSLAM_BUILD_BENCHMARKS=OFF "-DCMAKE_CXX_FLAGS=-fno-omit-frame-pointer" \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O3 -g -DNDEBUG" > "$OUT/cmake-prof.log"
  run cmake --build "$PBUILD" --target imm-monoslam -j"$JOBS" > "$OUT/build-prof.log" 2>&1
  profile() {  # name, args...
    local name="$1"; shift
    note_load "profile $name"
    run perf record -F 999 -g -o "$OUT/perf-$name.data" "$PBUILD/bin/imm-monoslam" "$ROOT/ini/imm7.ini" "$@" \
      --out "$OUT/prof-$name" --no-gui --quiet --set output.scene=false \
      --set slam.num_threads=1 > "$OUT/perf-$name.log" 2>&1
    perf report -i "$OUT/perf-$name.data" --no-children --sort symbol --percent-limit 0.7 --stdio 2>/dev/null \
      | grep -E '^ +[0-9.]+%' | cut -c1-170 | head -30 > "$OUT/perf-$name-self.txt" || true
    perf report -i "$OUT/perf-$name.data" --children --sort symbol --percent-limit 1 --stdio -g none 2>/dev/null \
      | grep -E '^ +[0-9.]+%' | grep -E 'immslam::(slam|bayes|frontend|shadow|system)' \
      | sed -E 's/\(anonymous namespace\)/(anon)/g; s/ +$//' | cut -c1-150 | head -40 > "$OUT/perf-$name-children.txt" || true
  }
  DATA="${IMMSLAM_SHARED_DATA_DIR:-$ROOT/../shared/data}"
  if [[ -f "$DATA/monoslam_testseq/rgb.txt" ]]; then
    profile testseq "$DATA/monoslam_testseq"
  fi
  profile paper --set "input.scenario=$ROOT/ini/scenarios/paper.ini"
fi

# ---- 4b. Instruction counts (optional)
if [[ "$CALLGRIND" -gt 0 ]]; then
  DATA="${IMMSLAM_SHARED_DATA_DIR:-$ROOT/../shared/data}"
  SEQS=()
  [[ -f "$DATA/monoslam_testseq/rgb.txt" ]] && SEQS+=(testseq)
  SEQS+=(paper)
  for seq in "${SEQS[@]}"; do
    for cfg in single imm7 imm7-shadow; do
      [[ -f "$ROOT/ini/$cfg.ini" ]] || continue
      note_load "callgrind $seq $cfg"
      if [[ $seq == testseq ]]; then IN=("$DATA/monoslam_testseq"); else IN=(--set "input.scenario=$ROOT/ini/scenarios/paper.ini"); fi
      run valgrind --tool=callgrind --callgrind-out-file="$OUT/cg-$seq-$cfg.out" "$BUILD/bin/imm-monoslam" \
        "$ROOT/ini/$cfg.ini" "${IN[@]}" --out "$OUT/cg-$seq-$cfg" --no-gui --quiet \
        --set output.scene=false --set slam.num_threads=1 --frames "$CALLGRIND" > "$OUT/cg-$seq-$cfg.log" 2>&1
      callgrind_annotate --inclusive=yes --threshold=100 "$OUT/cg-$seq-$cfg.out" 2>/dev/null \
        | grep -E '^ *[0-9,]+ \([ 0-9.]+%\)  [^=]' > "$OUT/cg-$seq-$cfg.txt" || true
    done
  done
fi

# ---- 5. The report
[[ $WRITE_DOC == 1 ]] || { echo "results in $OUT" >&2; exit 0; }
python3 - "$OUT" "$ROOT/doc/performance.md" "$MEM_CONFIG" "$LONG_FRAMES" <<'PY'
import csv, json, os, re, sys

out, doc, mem_config, long_frames = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])

def load(name):
    """Median aggregates (or the single run) of a Google Benchmark JSON file, by run_name."""
    p = os.path.join(out, name)
    res = {}
    if not os.path.exists(p):
        return res
    with open(p) as f:
        j = json.load(f)
    for b in j.get("benchmarks", []):
        if b.get("error_occurred"):
            continue
        if b.get("run_type") == "aggregate" and b.get("aggregate_name") != "median":
            continue
        if b.get("run_type") == "iteration" and b["run_name"] in res:
            continue
        res[b["run_name"]] = b
    return res

SCALE = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}
def wall(b):
    return b["real_time"] * SCALE[b["time_unit"]] if b else None
def cpu(b):
    return b["cpu_time"] * SCALE[b["time_unit"]] if b else None

def fmt(v, d=2):
    if v is None:
        return "–"
    if isinstance(v, str):
        return v
    a = abs(v)
    if a >= 100:
        return "%.0f" % v
    if a >= 10:
        return "%.1f" % v
    if a >= 0.1 or a == 0:
        return ("%." + str(d) + "f") % v
    return "%.3f" % v

def find(res, pattern):
    for k, b in res.items():
        if re.fullmatch(pattern, k):
            return b
    return None

def table(header, rows):
    s = "| " + " | ".join(header) + " |\n|" + "---|" * len(header) + "\n"
    for r in rows:
        s += "| " + " | ".join(c if isinstance(c, str) else fmt(c) for c in r) + " |\n"
    return s

def ratio(a, b):
    return a / b if a is not None and b else None

filt = load("bench_filter.json")
front = load("bench_frontend.json")
system = load("bench_system.json")
machine_all = open(os.path.join(out, "machine.txt")).read().strip().splitlines()
machine = [l for l in machine_all if not l.startswith("date:")]  # the doc says what is true, not when
loads = open(os.path.join(out, "loadavg.txt")).read().strip().splitlines()
cmds = open(os.path.join(out, "commands.txt")).read().strip()
sizes = [20, 50, 100, 150, 200]

md = []
md.append("# Performance\n")
md.append("Generated by `share/scripts/perf-report.sh` (do not edit the tables by hand: re-run the script; the "
          "hand-written section between the `manual` markers at the end is kept). Speed is measured and "
          "reported here, never asserted in CI. Every figure is the **median over the repetitions** "
          "(`--benchmark_repetitions`). *Wall* = elapsed time; *CPU* = CPU time of the benchmark's thread, "
          "the more robust figure on a loaded machine for single-threaded code.\n")
md.append("## Machine and build\n")
md.append("\n".join("- " + l for l in machine) + "\n")
md.append("\nLoad average (1, 5, 15 min) when each part started: with a load above the number of cores, wall "
          "times are inflated and the 2-thread figures pessimistic.\n")
md.append("\n".join("- " + l for l in loads) + "\n")

# ---- Targets
def sysb(seq):
    return find(system, r"BM_System/%s/.*" % re.escape(seq))
full = "imm7-shadow" if any("imm7-shadow_time_ms" in b for b in system.values()) else "imm7"
targets = []
t = sysb("monoslam_testseq")
if t:
    for c in (full, full + "-map60"):
        v = t.get(c + "_time_ms")
        if v is None:
            continue
        targets.append(["Full system (%s) on monoslam_testseq 320x240: median frame time" % c, "<= 33 ms (stretch 10 ms), map >= 60",
                        "%s ms, median map %d features" % (fmt(v), t.get(c + "_n_map", 0)),
                        ("yes (and stretch)" if v <= 10 else "yes (stretch no)" if v <= 33 else "no") +
                        ("" if t.get(c + "_n_map", 0) >= 60 else "; map < 60")])
for seq in ["monoslam_testseq", "visp_rbt", "rendered_handheld", "rendered_paper"]:
    b = sysb(seq)
    if b and b.get("ratio_imm7_single"):
        r1 = b.get("ratio_imm7_single_1t")
        targets.append(["imm7 / single median frame time, same run (%s)" % seq, "<= 3",
                        "%s (2 threads), %s (1 thread), %s exact IMM (2 threads)" %
                        (fmt(b["ratio_imm7_single"]), fmt(r1), fmt(b.get("ratio_imm7exact_single"))),
                        "yes" if b["ratio_imm7_single"] <= 3 else "no"])
v = sysb("visp_rbt")
if v and v.get(full + "_time_ms"):
    fps = 1000.0 / v[full + "_time_ms"]
    targets.append(["Full system (%s) on visp_rbt 640x480: frames/s (1000 / median frame ms)" % full, ">= 30",
                    fmt(fps), "yes" if fps >= 30 else "no"])
rss = []
if os.path.exists(os.path.join(out, "rss.csv")):
    with open(os.path.join(out, "rss.csv")) as f:
        rss = [dict((k, float(v)) for k, v in r.items()) for r in csv.DictReader(f)]
slope = None
if len(rss) > 8:
    half = [r for r in rss if r["frames"] >= rss[-1]["frames"] / 2]
    if len(half) > 3:
        xs = [r["frames"] for r in half]; ys = [r["vmrss_kb"] / 1024 for r in half]
        mx = sum(xs) / len(xs); my = sum(ys) / len(ys)
        den = sum((x - mx) ** 2 for x in xs)
        slope = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / den * 1000 if den > 0 else None
if slope is not None:
    targets.append(["Memory flat over a long rendered run (%s, %d frames): VmRSS slope over the 2nd half" % (mem_config, rss[-1]["frames"]),
                    "no growth (target run: 10 000 frames)", "%.2f MB / 1000 frames" % slope,
                    "yes" if abs(slope) < 0.5 else "no"])
md.append("\n## Targets\n")
if full != "imm7-shadow":
    md.append("ini/imm7-shadow.ini does not exist: the \"full system\" rows use ini/imm7.ini (no shadow filter).\n\n")
TARGETS_AT = len(md)
md.append("")

# ---- System
md.append("\n## Whole frames of the application (bench_system)\n")
md.append("`app::CImmMonoSlamApp` in-process on each sequence; every config runs back to back in the same "
          "repetition (same load). Medians over the frames (frame 0, the map initialisation, excluded) of the "
          "`frame_stats.csv` columns, then the median over the repetitions; ms. `time` is the whole frame; `slam` "
          "the SLAM filter = predict (mixing + mode-matched predictions) + search + ransac + update + map; "
          "`shadow` the shadow filter; `other` = time - slam (shadow filter, new-feature detection and "
          "initialisation). The `-1t` rows are the same configs with `--set slam.num_threads=1` (the shipped "
          "default is 2). `imm7-exact` is imm7 with `--set imm.dormant_below=0`: every mode updated every "
          "frame (the shipped bank leaves the modes the frame puts below the probability floor dormant, "
          "doc/imm.md). Rendered sequences are rendered on the fly (rendering is not counted).\n")
for name, b in sorted(system.items()):
    seq = name.split("/")[1]
    cfgs = [c for c in ["single", "single-1t", "imm7", "imm7-exact", "imm7-1t", "single-shadow", "imm7-shadow", "single-map60",
                        "imm7-map60", "imm7-shadow-map60"] if (c + "_time_ms") in b]
    rows = []
    for c in cfgs:
        g = lambda k: b.get(c + "_" + k)
        rows.append([c, g("time_ms"), g("slam_ms"), g("predict_ms"), g("search_ms"), g("ransac_ms"), g("update_ms"),
                     g("map_ms"), g("shadow_ms") if "shadow" in c else "–", g("other_ms"), "%d" % g("n_map"), "%d" % g("matched"),
                     "%d" % g("frames"), 1000.0 / g("time_ms") if g("time_ms") else None])
    md.append("\n### %s\n\n" % seq)
    md.append(table(["config", "time", "slam", "predict", "search", "ransac", "update", "map", "shadow", "other",
                     "map size", "matched", "frames", "frames/s"], rows))
    if b.get("ratio_imm7_single"):
        md.append("\nimm7 / single: %s whole frame, %s SLAM filter only (2 threads); %s with every mode updated "
                  "(imm7-exact); %s whole frame on 1 thread%s.\n" %
                  (fmt(b["ratio_imm7_single"]), fmt(b.get("ratio_imm7_single_slam")), fmt(b.get("ratio_imm7exact_single")),
                   fmt(b.get("ratio_imm7_single_1t")),
                   "; %s with the map of >= 60 features (`-map60`: `--set slam.min_visible_features=60`)" %
                   fmt(b["ratio_imm7_single_map60"]) if b.get("ratio_imm7_single_map60") else ""))

# ---- Instruction counts
FUNCS = [("frame (system)", "immslam::system::CMonoSlamSystem::processFrame"),
         ("SLAM filter", "immslam::slam::CMonoSlamIMM::processFrame"),
         ("predict", "immslam::slam::CMonoSlamIMM::predict"),
         ("  mix", "immslam::bayes::CIMMEstimator::mix"),
         ("  predictRobocentric", "immslam::slam::predictRobocentric"),
         ("search", "immslam::slam::CMonoSlamIMM::searchFeatures"),
         ("update", "immslam::slam::CMonoSlamIMM::updateBank"),
         ("  ekfUpdate", "immslam::bayes::ekfUpdate"),
         ("shadow filter", "immslam::shadow::CShadowFilter::processFrame")]
def cg(seq, cfg):
    p = os.path.join(out, "cg-%s-%s.txt" % (seq, cfg))
    if not os.path.exists(p):
        return None
    best = {}
    for line in open(p):
        m = re.match(r"\s*([0-9,]+) \([ 0-9.]+%\)  (.*)", line)
        if not m:
            continue
        ir = int(m.group(1).replace(",", ""))
        name = m.group(2)
        for _, fn in FUNCS:
            if re.search(r"(^|:)" + re.escape(fn) + r"\(", name) and "lambda" not in name:
                best[fn] = max(best.get(fn, 0), ir)
    frames = 0
    tp = os.path.join(out, "cg-%s-%s" % (seq, cfg), "trajectory.txt")
    if os.path.exists(tp):
        frames = sum(1 for _ in open(tp))
    return best, frames
cgseqs = [s_ for s_ in ("testseq", "paper") if cg(s_, "single")]
cg_targets = []
if cgseqs:
    md.append("\n## Instruction counts (callgrind; robust to the machine's load)\n\n")
    md.append("`valgrind --tool=callgrind` on the Release build, 1 thread, inclusive instructions per frame (millions) "
              "of the main functions. Instructions are not time (memory stalls and SIMD width are not counted) but "
              "they compare configurations without the noise of a shared machine.\n")
    for seq in cgseqs:
        cfgs = [c for c in ("single", "imm7", "imm7-shadow") if cg(seq, c)]
        data = {c: cg(seq, c) for c in cfgs}
        rows = []
        for label, fn in FUNCS:
            r = [label]
            for c in cfgs:
                best, frames = data[c]
                r.append(best[fn] / frames / 1e6 if fn in best and frames else None)
            if "single" in data and "imm7" in data:
                a_, b_ = r[1 + cfgs.index("imm7")], r[1 + cfgs.index("single")]
                r.append(ratio(a_, b_) if b_ and b_ > 0.05 else None)
            rows.append(r)
        md.append("\n%s (%d frames):\n\n" % ("monoslam_testseq" if seq == "testseq" else "ini/scenarios/paper.ini",
                                              data[cfgs[0]][1]))
        md.append(table(["M instructions / frame"] + cfgs + ["imm7/single"], rows))
        if "single" in data and "imm7" in data and rows[0][1]:
            cg_targets.append(["imm7 / single instructions per frame, same input (%s, callgrind)" %
                               ("monoslam_testseq" if seq == "testseq" else "paper scenario"), "<= 3",
                               "%s (whole frame), %s (SLAM filter)" % (fmt(rows[0][-1]), fmt(rows[1][-1])),
                               "yes" if rows[0][-1] and rows[0][-1] <= 3 else "no"])

md[TARGETS_AT] = table(["target", "wanted", "measured", "met"], targets + cg_targets)

# ---- Filter
md.append("\n## The filter alone (bench_filter)\n")
md.append("Measurement-level simulation (no images): a static cloud of N points in view of a gently oscillating "
          "320x240 camera, 30 features measured per frame (60 scalar measurements). One frame = "
          "`CMonoSlamIMM::processMeasurements()`: mixing, prediction of every mode, update of every mode, model "
          "probabilities, fused mean. ms per frame.\n\n")
md.append("All features inverse depth (n = 13 + 6N, the worst case), 1 and 2 threads (wall time):\n\n")
rows = []
for N in sizes:
    v = {}
    for bank in (1, 7):
        for th in (1, 2):
            v[(bank, th)] = find(filt, r"BM_FilterFrame/N:%d/bank:%d/threads:%d/.*" % (N, bank, th))
    if not any(v.values()):
        continue
    rows.append([str(N), "%d" % (13 + 6 * N), wall(v[(1, 1)]), wall(v[(1, 2)]), wall(v[(7, 1)]), wall(v[(7, 2)]),
                 ratio(cpu(v[(7, 1)]), cpu(v[(1, 1)])), ratio(wall(v[(7, 1)]), wall(v[(7, 2)]))])
md.append(table(["N", "n", "single 1T", "single 2T", "imm7 1T", "imm7 2T", "imm7/single (1T, CPU)",
                 "imm7 speed-up 1T -> 2T"], rows))
rows = []
for N in sizes:
    s1 = find(filt, r"BM_FilterFrameXYZ/N:%d/bank:1/.*" % N); i7 = find(filt, r"BM_FilterFrameXYZ/N:%d/bank:7/.*" % N)
    if s1 or i7:
        rows.append([str(N), "%d" % (s1 or i7)["n"], cpu(s1), cpu(i7), ratio(cpu(i7), cpu(s1))])
if rows:
    md.append("\nXYZ map (n = 13 + 3N: the real runs' maps are mostly XYZ), 1 thread, CPU ms per frame:\n\n")
    md.append(table(["N", "n", "single", "imm7", "imm7/single"], rows))

md.append("\n### Pieces (micro-benchmarks; CPU time unless marked 2T = wall time with 2 threads)\n\n")
rows = []
for N in sizes:
    m1 = find(filt, r"BM_Mix/N:%d/threads:1/.*" % N); m2 = find(filt, r"BM_Mix/N:%d/threads:2/.*" % N)
    cp = find(filt, r"BM_CopyBank/N:%d.*" % N)
    c1 = find(filt, r"BM_CombineFull/N:%d/threads:1/.*" % N); c2 = find(filt, r"BM_CombineFull/N:%d/threads:2/.*" % N)
    cm = find(filt, r"BM_CombineMean/N:%d.*" % N); cc = find(filt, r"BM_CombinedColumns/N:%d.*" % N)
    if not (m1 or cp or c1):
        continue
    rows.append([str(N), "%d" % (13 + 6 * N), cpu(m1), wall(m2), cpu(cp), cpu(c1), wall(c2),
                 cpu(cm) * 1000 if cm else None, cpu(cc) * 1000 if cc else None])
md.append("Mixing (`CIMMEstimator::mix`, 7 modes), its memory-traffic floor (copying the 7 covariances), the "
          "combination of the modes (`combine` with the full covariance, mean only, and `combinedColumns` of one "
          "feature, per RANSAC hypothesis), inverse-depth maps:\n\n")
md.append(table(["N", "n", "mix ms", "mix 2T ms", "copy 7 P ms", "combine full ms", "combine full 2T ms",
                 "combine mean µs", "combinedColumns µs"], rows))
rows = []
for N in (20, 200):
    for ln in (1, 6):
        b = find(filt, r"BM_CombinedBlock/N:%d/len:%d.*" % (N, ln))
        if b: rows.append([str(N), str(ln), cpu(b) * 1000])
if rows:
    md.append("\n`combinedBlock` (one feature's block of the fused covariance: per searched feature and per depth "
              "test), µs:\n\n")
    md.append(table(["N", "len", "µs"], rows))
rows = []
for N in sizes:
    r = [str(N), "%d" % (13 + 6 * N)]
    for m in (40, 60, 80):
        b = find(filt, r"BM_EkfUpdate/N:%d/m:%d.*" % (N, m))
        r.append(cpu(b))
    if any(x is not None for x in r[2:]):
        rows.append(r)
md.append("\n`bayes::ekfUpdate` of one mode, n x n covariance, m scalar measurements (m/2 features), ms:\n\n")
md.append(table(["N", "n", "m = 40", "m = 60", "m = 80"], rows))
rows = []
names = ["stationary", "stationary, shake 0.1 px", "rotation", "general"]
for N in sizes:
    r = [str(N), "%d" % (13 + 6 * N)]
    for fam in range(4):
        r.append(cpu(find(filt, r"BM_PredictRobocentric/N:%d/model:%d.*" % (N, fam))))
    if any(x is not None for x in r[2:]):
        rows.append(r)
md.append("\n`slam::predictRobocentric` of one mode (inverse-depth map), ms:\n\n")
md.append(table(["N", "n"] + names, rows))

p1 = find(filt, r"BM_ParallelForOverhead/threads:1.*"); p2 = find(filt, r"BM_ParallelForOverhead/threads:2.*")
if p1 or p2:
    md.append("\nFixed cost of one `CThreadPool::parallelFor` over the 7 modes with no work (wall µs; a frame makes "
              "~5 such calls): %s µs with 1 thread (inline), %s µs with 2 threads.\n" %
              (fmt(wall(p1) * 1000 if p1 else None), fmt(wall(p2) * 1000 if p2 else None)))

# ---- Prototypes and wider SIMD: experiments, not the library's speed; written to OUT/prototypes.md for
# doc/experiments/performance.md, not to doc/performance.md.
date = [l for l in machine_all if l.startswith("date:")]
pr = ["# Prototype kernels and wider SIMD\n",
      "Written by `share/scripts/perf-report.sh` beside its raw results; %s; machine and commands as in "
      "doc/performance.md of the same run.\n" % (date[0] if date else "date unknown")]
pr.append("\n### Prototype kernels (tests/benchmarks/bench_kernels.cpp: not used by the library)\n\n")
pr.append("Same data as the library's kernels; `max_abs_diff` is the largest difference from the library's result.\n\n")
rows = []
for N in (20, 40, 100, 150, 200):
    r = [str(N), "%d" % (13 + 6 * N)]
    for th in (1, 2):
        for var in (0, 1, 2):
            b = find(filt, r"BM_ProtoMix/N:%d/threads:%d/variant:%d/.*" % (N, th, var))
            r.append(wall(b) if th == 2 else cpu(b))
    if any(x is not None for x in r[2:]):
        rows.append(r)
if rows:
    pr.append("\nMixing, 7 modes: library vs the structured-Markov-matrix algebra (one common sum S + T, then "
              "each output = a S + b P_i + two rank-1 terms) in 2-D tiles + blocked mirror, or column by column over "
              "the full matrix (no mirror), ms:\n\n")
    pr.append(table(["N", "n", "library", "tiles", "columns", "library 2T", "tiles 2T", "columns 2T"], rows))
rows = []
for N in (50, 100, 150, 200):
    a = find(filt, r"BM_ProtoMirror/N:%d/variant:0.*" % N); b = find(filt, r"BM_ProtoMirror/N:%d/variant:1.*" % N)
    if a:
        rows.append([str(N), "%d" % (13 + 6 * N), cpu(a), cpu(b)])
if rows:
    pr.append("\nMirroring the lower triangle (after every symmetric update), one matrix in cache, ms:\n\n")
    pr.append(table(["N", "n", "Eigen transpose", "blocked 32x32"], rows))
rows = []
for N in (100, 150, 200):
    r = [str(N), "%d" % (13 + 6 * N)]
    for var in (0, 1, 2):
        r.append(cpu(find(filt, r"BM_ProtoDowndate/N:%d/m:60/variant:%d.*" % (N, var))))
    if any(x is not None for x in r[2:]):
        rows.append(r)
if rows:
    pr.append("\nCovariance downdate P -= Z^T Z of the EKF update (m = 60), ms:\n\n")
    pr.append(table(["N", "n", "rankUpdate + Eigen mirror (library)", "rankUpdate + blocked mirror", "full GEMM"], rows))

rows = []
for N in (40, 150):
    for xyz in (1, 0):
        a = find(filt, r"BM_ProtoEkfUpdate/N:%d/xyz:%d/mfeat:23/variant:0.*" % (N, xyz))
        b = find(filt, r"BM_ProtoEkfUpdate/N:%d/xyz:%d/mfeat:23/variant:1.*" % (N, xyz))
        if a and b:
            rows.append([str(N), "XYZ" if xyz else "inverse depth", "%d" % a["n"], cpu(a) * 1000, cpu(b) * 1000,
                         ratio(cpu(a), cpu(b)), "%.1e" % b.get("max_abs_diff", 0)])
if rows:
    pr.append("\n`ekfUpdate` (m = 46): library vs P H^T and H (P H^T) from compile-time 2x3 / 2x6 blocks, µs:\n\n")
    pr.append(table(["N", "map", "n", "library µs", "fixed-size µs", "speed-up", "max_abs_diff"], rows))

# ---- SIMD
sse, avx = load("bench_simd_sse2.json"), load("bench_simd_avx2.json")
if sse:
    pr.append("\n### Wider SIMD (bench_simd_sse2 vs bench_simd_avx2)\n\n")
    pr.append("The same dense kernels in plain Eigen compiled with the project's flags (x86-64 baseline: SSE2) and "
              "with `-mavx2 -mfma -DEIGEN_MAX_ALIGN_BYTES=16` (Eigen's object layout unchanged: ABI-compatible "
              "with Debian's MRPT). m = 46. CPU µs:\n\n")
    rows = []
    for kern, label in (("BM_Downdate", "downdate P -= Z^T Z + mirror"), ("BM_TriangularSolve", "triangular solve L^-1 (PH^T)^T"),
                        ("BM_MixKernel", "mixing inner loop (7 x 7 + spread, 1 bank)"), ("BM_PredictBlocks", "prediction block products (6-blocks)")):
        for n in (133, 253, 463, 913):
            a = find(sse, r"%s/n:%d(/m:46)?" % (kern, n)); b = find(avx, r"%s/n:%d(/m:46)?" % (kern, n))
            if a:
                rows.append([label, str(n), cpu(a) * 1000, cpu(b) * 1000 if b else None, ratio(cpu(a), cpu(b))])
    pr.append(table(["kernel", "n", "SSE2 µs", "AVX2+FMA µs", "speed-up"], rows))

# ---- Front end
md.append("\n## Front end (bench_frontend)\n")
rows = []
for w in (320, 640):
    for occ in (0, 30):
        b = find(front, r"BM_DetectInEmptyCells/width:%d/occupied:%d.*" % (w, occ))
        if b: rows.append(["%dx%d" % (w, w * 3 // 4), "%d new, %d tracked" % (30 if occ == 0 else 10, occ),
                           cpu(b), "%d" % b.get("corners", 0), b.get("label", "")])
md.append("`frontend::detectInEmptyCells` (FAST + Shi-Tomasi at the candidates, 8x6 grid), ms:\n\n")
md.append(table(["image", "corners wanted", "ms", "found", "frame"], rows))
rows = []
for w in (320, 640):
    for a in (100, 400, 1600, 6400):
        b = find(front, r"BM_SearchInEllipse/width:%d/area_px2:%d.*" % (w, a))
        nb = find(front, r"BM_SearchInEllipseNoWorkspace/width:%d/area_px2:%d.*" % (w, a))
        if b: rows.append(["%dx%d" % (w, w * 3 // 4), str(a), cpu(b) * 1000, cpu(nb) * 1000 if nb else None,
                           "%d" % b.get("positions", 0), "%.2f" % b.get("found_frac", 0)])
md.append("\n`frontend::searchInEllipse` (ZNCC of an 11x11 template at every position of the 95 % ellipse, "
          "sub-pixel refinement), µs per search, with a reused workspace and without one (what "
          "`CSlamTracker::searchFeatures` does):\n\n")
md.append(table(["image", "ellipse area px²", "µs (workspace)", "µs (no workspace)", "positions", "found"], rows))
b = find(front, r"BM_PredictTemplate.*")
if b:
    md.append("\nPatch prediction (`CFeaturePatch::predictTemplate`, affine warp): %s µs per feature.\n" % fmt(cpu(b) * 1000))

# ---- Memory
md.append("\n## Memory\n")
if rss:
    pk = os.path.join(out, "memory-run", "maxrss_kb.txt")
    peak = open(pk).read().strip().splitlines()[-1] if os.path.exists(pk) else ""
    md.append("`imm-monoslam ini/%s.ini` on ini/scenarios/handheld.ini lengthened to %d frames (rendered on the "
              "fly; the renderer's memory is included), VmRSS sampled every 0.5 s:\n\n" % (mem_config, long_frames))
    rows = []
    last = rss[-1]["frames"]
    seen = set()
    for q in (0.02, 0.1, 0.25, 0.5, 0.75, 1.0):
        r = min(rss, key=lambda r: abs(r["frames"] - q * last))
        if r["frames"] in seen:
            continue
        seen.add(r["frames"])
        rows.append(["%d" % r["frames"], "%.0f" % r["seconds"], "%.1f" % (r["vmrss_kb"] / 1024), "%.1f" % (r["vmhwm_kb"] / 1024)])
    md.append(table(["frames done", "s", "VmRSS MB", "VmHWM MB"], rows))
    fs = os.path.join(out, "memory-run", "frame_stats.csv")
    nmap = ""
    if os.path.exists(fs):
        with open(fs) as f:
            st = list(csv.DictReader(f))
        if st:
            nm = [int(r["n_map"]) for r in st]
            nmap = " SLAM map size: max %d, at the end %d." % (max(nm), nm[-1])
    md.append("\nPeak RSS (`/usr/bin/time -f %%M`): %s MB. VmRSS slope over the second half of the run: %s MB per 1000 "
              "frames.%s\n" % ("%.1f" % (int(peak) / 1024) if peak.isdigit() else "–",
                             "%.2f" % slope if slope is not None else "–", nmap))

# ---- Profiles
for name in ("testseq", "paper"):
    p = os.path.join(out, "perf-%s-children.txt" % name)
    if os.path.exists(p) and os.path.getsize(p) > 0:
        md.append("\n## Profile: imm7 on %s (perf, inclusive time, -O3 -g -fno-omit-frame-pointer)\n\n```\n%s\n```\n" %
                  ("monoslam_testseq" if name == "testseq" else "ini/scenarios/paper.ini", open(p).read().rstrip()))

# ---- Commands
md.append("\n## Commands\n\nExactly what produced this file (paths relative to the project root; the raw JSON "
          "and CSV files stay in the script's --out folder):\n\n```\nshare/scripts/perf-report.sh " +
          os.environ.get("PERF_REPORT_ARGS", "") + "\n" + cmds + "\n```\n")

manual = ""
if os.path.exists(doc):
    m = re.search(r"<!-- manual:begin -->.*?<!-- manual:end -->", open(doc).read(), re.S)
    if m:
        manual = m.group(0)
if not manual:
    manual = "<!-- manual:begin -->\n## Analysis (hand-written)\n\n(none yet)\n<!-- manual:end -->"
md.append("\n" + manual + "\n")
with open(doc, "w") as f:
    f.write("\n".join(md))
print("wrote", doc)
if any(x.startswith("| ") for x in pr):
    with open(os.path.join(out, "prototypes.md"), "w") as f:
        f.write("\n".join(pr))
    print("wrote", os.path.join(out, "prototypes.md"), "(for doc/experiments/performance.md)")
PY
