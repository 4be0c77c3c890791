#!/usr/bin/env python3
import sys, math
# Davison's one-parameter model (r_u = r_d / sqrt(1 - 2 kd1 r_d^2), pixels) as COLMAP's OPENCV_FISHEYE
# (r_d / f = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8), theta = atan(r_u / f)):
# least-squares k1..k4 over the image radius (0 .. farthest corner), residual printed to stderr.
w, h, f, cx, cy, kd1 = map(float, sys.argv[1:7])
rmax = max(math.hypot(x - cx, y - cy) for x in (0, w) for y in (0, h))
if 2 * kd1 * rmax * rmax >= 1:
    sys.exit('make-reference: kd1 %g has no undistortion at the image corner (2 kd1 r^2 >= 1)' % kd1)
rows = []
for i in range(1, 401):
    rd = rmax * i / 400
    th = math.atan(rd / math.sqrt(1 - 2 * kd1 * rd * rd) / f)
    rows.append(([th ** 3, th ** 5, th ** 7, th ** 9], rd / f - th))
A = [[sum(r[0][i] * r[0][j] for r in rows) for j in range(4)] + [sum(r[0][i] * r[1] for r in rows)] for i in range(4)]
for c in range(4):  # Gauss-Jordan on the normal equations, partial pivoting
    p = max(range(c, 4), key=lambda r: abs(A[r][c])); A[c], A[p] = A[p], A[c]
    for r in range(4):
        if r != c:
            m = A[r][c] / A[c][c]; A[r] = [a - m * b for a, b in zip(A[r], A[c])]
k = [A[i][4] / A[i][i] for i in range(4)]
res = max(abs(sum(a * b for a, b in zip(x, k)) - y) for x, y in rows) * f
print('make-reference: OPENCV_FISHEYE fit of Davison kd1 %g: max %.2g px over r_d <= %.1f px' % (kd1, res, rmax), file=sys.stderr)
print(','.join('%.10g' % v for v in k))
