#!/usr/bin/env python3
"""imm-monoslam: draws the figures of a run from the CSV files in its output folder.

    share/scripts/plot-run.py RUN_DIR [--out DIR]

Reads what `imm-monoslam ... --out RUN_DIR` wrote and writes, into RUN_DIR (or DIR):
  model_probabilities.png      posterior model probabilities mu_k over time, stacked to 1 (the IMM
                               paper's Fig. 4), with the true motion as a band under the axes when
                               the run wrote motion_labels.csv (rendered inputs, dataset folders
                               with motion_labels.txt)
  model_probabilities_log.png  the same as lines on a log axis (10^-4 to 1), as the paper draws them
  search_area.png              mean area of the 95 % search ellipses (frame_stats.csv
                               mean_search_area_px2), log axis
  ate.png                      position error after Sim(3) alignment over time (ate.csv: only when
                               the input had ground truth)
Needs python3-matplotlib (Debian; share/scripts/install-deps.sh installs it). Exit status 0 on
success, 1 on a missing or malformed file (the message names it), 2 on bad usage.
"""
import argparse
import csv
import os
import sys

FAMILIES = ("stationary", "rotation", "general")
# Light and dark end of each family's colour ramp (RGB 0-255): first model of a family the
# lightest, last the darkest, so the 7 models of the paper read as 3 families.
RAMP_LIGHT = {"stationary": (150, 150, 150), "rotation": (150, 195, 240), "general": (253, 195, 110)}
RAMP_DARK = {"stationary": (70, 70, 70), "rotation": (20, 60, 150), "general": (185, 30, 20)}
FAMILY_COLOUR = {"stationary": (110, 110, 110), "rotation": (60, 120, 210), "general": (235, 120, 30)}
OTHERS = [(0, 114, 178), (230, 159, 0), (0, 158, 115), (204, 121, 167), (86, 180, 233), (213, 94, 0),
          (240, 228, 66), (0, 0, 0)]
MIN_PROBABILITY = 1e-4


class RunError(Exception):
    """A missing or malformed input file; the message names it."""


def rgb(c):
    return tuple(v / 255.0 for v in c)


def family(name):
    for f in FAMILIES:
        if name.startswith(f):
            return f
    return None


def model_colours(names):
    """One colour per model: a ramp per family (light to dark in column order), others distinct."""
    count = {f: sum(1 for n in names if family(n) == f) for f in FAMILIES}
    seen = {f: 0 for f in FAMILIES}
    out, other = [], 0
    for n in names:
        f = family(n)
        if f is None:
            out.append(rgb(OTHERS[other % len(OTHERS)]))
            other += 1
            continue
        t = seen[f] / (count[f] - 1) if count[f] > 1 else 0.5
        a, b = RAMP_LIGHT[f], RAMP_DARK[f]
        out.append(rgb(tuple(x + (y - x) * t for x, y in zip(a, b))))
        seen[f] += 1
    return out


def read_csv(path, required):
    """Header and rows of a CSV file; every column in `required` must be in the header."""
    if not os.path.isfile(path):
        raise RunError("%s: no such file" % path)
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows:
        raise RunError("%s: empty (no header)" % path)
    header = rows[0]
    for c in required:
        if c not in header:
            raise RunError("%s:1: no column '%s' in the header" % (path, c))
    return header, rows[1:]


def number(path, line, text):
    try:
        return float(text)
    except ValueError:
        raise RunError("%s:%d: '%s' is not a number" % (path, line, text))


def read_probabilities(run):
    path = os.path.join(run, "model_probabilities.csv")
    header, rows = read_csv(path, ["timestamp"])
    names = header[1:]
    if not names:
        raise RunError("%s:1: no model columns after timestamp" % path)
    times, probs = [], []
    for i, r in enumerate(rows, start=2):
        if len(r) != len(header):
            raise RunError("%s:%d: %d cells, the header has %d" % (path, i, len(r), len(header)))
        times.append(number(path, i, r[0]))
        probs.append([number(path, i, c) for c in r[1:]])
    if not times:
        raise RunError("%s: no frames" % path)
    return times, names, probs


def read_labels(run, times):
    """True motion label per frame of model_probabilities.csv (None where unknown), or None."""
    path = os.path.join(run, "motion_labels.csv")
    if not os.path.isfile(path):
        return None
    _, rows = read_csv(path, ["timestamp", "label"])
    by_time = {}
    for i, r in enumerate(rows, start=2):
        if len(r) < 2:
            raise RunError("%s:%d: expected timestamp,label" % (path, i))
        by_time[round(number(path, i, r[0]) * 1e6)] = r[1]
    labels = [by_time.get(round(t * 1e6)) for t in times]
    return labels if any(labels) else None


def draw_band(ax, times, labels):
    """The true motion as coloured spans under the probabilities, one per run of equal labels."""
    import matplotlib.patches as mpatches
    step = (times[-1] - times[0]) / max(1, len(times) - 1)
    cats = []
    start = 0
    for k in range(1, len(times) + 1):
        if k == len(times) or labels[k] != labels[start]:
            lab = labels[start]
            if lab:
                end = times[k] if k < len(times) else times[-1] + step
                ax.axvspan(times[start], end, color=rgb(FAMILY_COLOUR.get(family(lab) or "", (190, 190, 190))), lw=0)
                if lab not in cats:
                    cats.append(lab)
            start = k
    ax.set_yticks([])
    ax.set_ylabel("truth", rotation=0, ha="right", va="center")
    return [mpatches.Patch(color=rgb(FAMILY_COLOUR.get(family(c) or "", (190, 190, 190))), label="truth: " + c)
            for c in cats]


def plot_probabilities(run, out, plt):
    times, names, probs = read_probabilities(run)
    labels = read_labels(run, times)
    colours = model_colours(names)
    cols = list(zip(*probs))
    written = []
    for log in (False, True):
        if labels:
            fig, (ax, band) = plt.subplots(2, 1, sharex=True, figsize=(10, 4.6),
                                           gridspec_kw={"height_ratios": [12, 1], "hspace": 0.08})
        else:
            fig, ax = plt.subplots(figsize=(10, 4.6))
            band = None
        if log:
            for name, c, y in zip(names, colours, cols):
                ax.plot(times, [max(v, MIN_PROBABILITY) for v in y], color=c, lw=1.5, label=name)
            ax.set_yscale("log")
            ax.set_ylim(MIN_PROBABILITY, 1.0)
        else:
            ax.stackplot(times, cols, colors=colours, labels=names, lw=0)
            ax.set_ylim(0.0, 1.0)
        ax.set_xlim(times[0], max(times[-1], times[0] + 1e-9))
        ax.set_title("Posterior model probabilities")
        ax.set_ylabel("probability")
        handles, _ = ax.get_legend_handles_labels()
        if band is not None:
            handles += draw_band(band, times, labels)
            band.set_xlabel("time [s]")
        else:
            ax.set_xlabel("time [s]")
        ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small", frameon=False)
        name = "model_probabilities_log.png" if log else "model_probabilities.png"
        fig.savefig(os.path.join(out, name), dpi=100, bbox_inches="tight")
        plt.close(fig)
        written.append(name)
    return written, names


def plot_search_area(run, out, plt, names):
    path = os.path.join(run, "frame_stats.csv")
    header, rows = read_csv(path, ["timestamp", "mean_search_area_px2"])
    it, ia = header.index("timestamp"), header.index("mean_search_area_px2")
    x, y = [], []
    for i, r in enumerate(rows, start=2):
        if len(r) <= max(it, ia):
            raise RunError("%s:%d: %d cells, the header has %d" % (path, i, len(r), len(header)))
        a = number(path, i, r[ia])
        if a > 0:
            x.append(number(path, i, r[it]))
            y.append(a)
    if not x:
        return []
    label = "IMM (%d models)" % len(names) if len(names) > 1 else names[0]
    fig, ax = plt.subplots(figsize=(9, 4.2))
    ax.plot(x, y, color=rgb(OTHERS[0]), lw=1.2, label=label)
    ax.set_yscale("log")
    ax.set_title("Mean search-ellipse area (95 %)")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("area [px^2]")
    ax.legend(loc="best", fontsize="small")
    fig.savefig(os.path.join(out, "search_area.png"), dpi=100, bbox_inches="tight")
    plt.close(fig)
    return ["search_area.png"]


def plot_ate(run, out, plt):
    path = os.path.join(run, "ate.csv")
    if not os.path.isfile(path):
        return []
    header, rows = read_csv(path, ["timestamp", "position_error"])
    it, ie = header.index("timestamp"), header.index("position_error")
    x = [number(path, i, r[it]) for i, r in enumerate(rows, start=2)]
    y = [number(path, i, r[ie]) for i, r in enumerate(rows, start=2)]
    if not x:
        return []
    fig, ax = plt.subplots(figsize=(9, 4.2))
    ax.plot(x, y, color=rgb(OTHERS[0]), lw=1.2, label="ATE")
    ax.set_title("Absolute trajectory error after Sim(3) alignment")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("position error [ground-truth units]")
    ax.set_ylim(bottom=0)
    ax.legend(loc="best", fontsize="small")
    fig.savefig(os.path.join(out, "ate.png"), dpi=100, bbox_inches="tight")
    plt.close(fig)
    return ["ate.png"]


def main():
    p = argparse.ArgumentParser(description="Draws the figures of an imm-monoslam run from its CSV files.")
    p.add_argument("run_dir", help="output folder of imm-monoslam (--out)")
    p.add_argument("--out", help="folder for the PNG files (default: RUN_DIR)")
    a = p.parse_args()
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("plot-run.py: matplotlib is missing (Debian: apt-get install python3-matplotlib, then run "
              "this script with /usr/bin/python3)", file=sys.stderr)
        return 1
    out = a.out or a.run_dir
    if not os.path.isdir(a.run_dir):
        print("plot-run.py: %s: not a folder" % a.run_dir, file=sys.stderr)
        return 1
    os.makedirs(out, exist_ok=True)
    try:
        written, names = plot_probabilities(a.run_dir, out, plt)
        written += plot_search_area(a.run_dir, out, plt, names)
        written += plot_ate(a.run_dir, out, plt)
    except RunError as e:
        print("plot-run.py: %s" % e, file=sys.stderr)
        return 1
    for w in written:
        print(os.path.join(out, w))
    return 0


if __name__ == "__main__":
    sys.exit(main())
