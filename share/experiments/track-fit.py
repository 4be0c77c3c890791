#!/usr/bin/env python3
"""Whether the shadow filter's decided tracks are static points: each decision's track (its measured
pixels from the feature's birth to the decision, from shadow_log.csv) triangulated as one static point
under each given trajectory, and the RMS of its reprojection in pixels; also over the views since the
track's last miss. A track that fits no trajectory is a tracking error (a slide, a jump to another
point), not a mover the relative motion hides (doc/shadow.md, "A static real scene over RANSAC draws").
Usage: share/experiments/track-fit.py RUN_DIR CALIB NAME=TRAJECTORY [NAME=TRAJECTORY ...]
  RUN_DIR: an imm-monoslam output folder run with --set output.search_log=true (shadow_log.csv,
  classifications.csv); CALIB: the sequence's calib.txt (pinhole; other models are read as pinhole,
  their distortion ignored); TRAJECTORY: TUM files (T_world_camera), e.g. the run's trajectory.txt,
  trajectory_smoothed.txt, a COLMAP reference (share/experiments/make-reference.sh). Timestamps are
  matched to 1e-4 s. Needs python3-numpy and python3-scipy (apt-get install).
Prints one row per decision: class, feature id, time, measured views, misses, then per trajectory the
RMS over all views and over the views after the last miss (nan: fewer than 3 views or a missing pose)."""
import csv
import sys

import numpy as np
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation


def read_tum(path):
    poses = {}
    with open(path) as f:
        for line in f:
            if line.startswith('#') or not line.strip():
                continue
            v = [float(x) for x in line.split()]
            poses[round(v[0], 4)] = (Rotation.from_quat(v[4:8]).as_matrix(), np.array(v[1:4]))
    return poses


def read_calib(path):
    with open(path) as f:
        for line in f:
            if not line.startswith('#') and line.strip():
                return [float(x) for x in line.split()[3:7]]
    sys.exit('track-fit: %s has no calibration line' % path)


def static_fit_rms(views, poses, calib):
    """RMS reprojection (px) of the best static point for the views (t, u, v), or None."""
    fx, fy, cx, cy = calib
    obs = [(poses[t], u, v) for t, u, v in views if t in poses]
    if len(obs) < 3 or len(obs) < len(views):
        return None
    A, b = np.zeros((3, 3)), np.zeros(3)
    for (R, c), u, v in obs:  # the point nearest every ray, to start from
        d = R @ np.array([(u - cx) / fx, (v - cy) / fy, 1.0])
        d /= np.linalg.norm(d)
        P = np.eye(3) - np.outer(d, d)
        A += P
        b += P @ c
    X0 = np.linalg.lstsq(A, b, rcond=None)[0]

    def residuals(X):
        r = []
        for (R, c), u, v in obs:
            p = R.T @ (X - c)
            z = p[2] if abs(p[2]) > 1e-9 else 1e-9
            r += [fx * p[0] / z + cx - u, fy * p[1] / z + cy - v]
        return np.array(r)

    r = least_squares(residuals, X0, method='lm').fun.reshape(-1, 2)
    return float(np.sqrt((r ** 2).sum(axis=1).mean()))


def main(argv):
    if len(argv) < 4 or argv[1] in ('-h', '--help'):
        print(__doc__.strip())
        return 0 if len(argv) > 1 and argv[1] in ('-h', '--help') else 2
    run, calib = argv[1], read_calib(argv[2])
    trajectories = []
    for arg in argv[3:]:
        if '=' not in arg:
            sys.exit("track-fit: '%s' is not NAME=TRAJECTORY" % arg)
        name, path = arg.split('=', 1)
        trajectories.append((name, read_tum(path)))
    frames = {}
    with open(run + '/shadow_log.csv') as f:
        for row in csv.DictReader(f):
            frames.setdefault(row['feature_id'], []).append(
                (round(float(row['timestamp']), 4), row['measured'] == '1', float(row['u']), float(row['v'])))
    print('class feature t views misses ' + ' '.join('%s %s_after_miss' % (n, n) for n, _ in trajectories))
    with open(run + '/classifications.csv') as f:
        for row in csv.DictReader(f):
            t = round(float(row['timestamp']), 4)
            seen = [x for x in frames.get(row['feature_id'], []) if x[0] <= t + 1e-6]
            measured = [i for i, x in enumerate(seen) if x[1]]
            if len(measured) < 3:
                continue
            gaps = [b for a, b in zip(measured, measured[1:]) if b - a > 1]
            views = [(x[0], x[2], x[3]) for x in seen if x[1]]
            tail = [(x[0], x[2], x[3]) for x in seen[gaps[-1] if gaps else 0:] if x[1]]
            cells = []
            for _, poses in trajectories:
                for v in (views, tail):
                    rms = static_fit_rms(v, poses, calib)
                    cells.append('nan' if rms is None else '%.2f' % rms)
            print(row['class'], row['feature_id'], '%.3f' % t, len(views), len(gaps), ' '.join(cells))
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv))
