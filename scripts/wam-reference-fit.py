#!/usr/bin/env python3
"""An independent least-squares fit of the rigid model of the shared Barrett WAM grid
(../shared/data/wam-grid, docs/results.md "A seven-axis arm"): every DH element of the seven
joints, the SMR point in the flange frame and the base -> tracker transform, fitted by
Levenberg-Marquardt (pure Python, numeric Jacobian, no library of hivecal's) from several starts
to the training poses of a hivecal result, and scored on its test poses.

  scripts/wam-reference-fit.py GRID.csv RESULT.json [STARTS]

RESULT.json is what `hivecal calibrate` wrote for that grid: its report's samples say which
poses trained (matched to the grid's rows by their measured point). Prints the best start's
training RMS, its test MAE (3-D, mm) and the result's own test MAE beside it.
"""
import csv
import json
import math
import random
import sys

# The published WAM standard DH (the grid's README): a, alpha, d per joint [m, rad]; SMR 44 mm out.
A_M = [0.0, 0.0, 0.045, -0.045, 0.0, 0.0, 0.0]
ALPHA_RAD = [-math.pi / 2, math.pi / 2, -math.pi / 2, math.pi / 2, -math.pi / 2, math.pi / 2, 0.0]
D_M = [0.0, 0.0, 0.55, 0.0, 0.3, 0.0, 0.06]
TOOL_M = [0.0, 0.0, 0.044]
JOINTS = 7
PARAMS = 4 * JOINTS + 3 + 6  # theta, d, a, alpha per joint; tool; base rotation vector, translation


def matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def dh(theta, d, a, alpha):
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return [[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0.0, sa, ca, d], [0.0, 0.0, 0.0, 1.0]]


def rotation(v):
    angle = math.sqrt(sum(x * x for x in v))
    if angle < 1e-300:
        return [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    x, y, z = (c / angle for c in v)
    c, s, t = math.cos(angle), math.sin(angle), 1.0 - math.cos(angle)
    return [[t * x * x + c, t * x * y - s * z, t * x * z + s * y], [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
            [t * x * z - s * y, t * y * z + s * x, t * z * z + c]]


def predict(p, q):
    t = [[1.0 if i == j else 0.0 for j in range(4)] for i in range(4)]
    for j in range(JOINTS):
        t = matmul(t, dh(q[j] + p[4 * j], p[4 * j + 1], p[4 * j + 2], p[4 * j + 3]))
    tool = p[4 * JOINTS:4 * JOINTS + 3]
    base = [sum(t[i][k] * tool[k] for k in range(3)) + t[i][3] for i in range(3)]
    r = rotation(p[4 * JOINTS + 3:4 * JOINTS + 6])
    shift = p[4 * JOINTS + 6:4 * JOINTS + 9]
    return [sum(r[i][k] * base[k] for k in range(3)) + shift[i] for i in range(3)]


def residuals(p, poses):
    out = []
    for q, measured in poses:
        point = predict(p, q)
        out.extend(point[i] - measured[i] for i in range(3))
    return out


def solve(a, b):
    """x = a^-1 b by Cholesky (a symmetric positive definite)."""
    n = len(b)
    low = [[0.0] * n for _ in range(n)]
    for i in range(n):
        for j in range(i + 1):
            s = a[i][j] - sum(low[i][k] * low[j][k] for k in range(j))
            if i == j:
                if s <= 0.0:
                    return None
                low[i][i] = math.sqrt(s)
            else:
                low[i][j] = s / low[j][j]
    y = [0.0] * n
    for i in range(n):
        y[i] = (b[i] - sum(low[i][k] * y[k] for k in range(i))) / low[i][i]
    x = [0.0] * n
    for i in reversed(range(n)):
        x[i] = (y[i] - sum(low[k][i] * x[k] for k in range(i + 1, n))) / low[i][i]
    return x


def fit(start, poses, iterations=200):
    p = list(start)
    r = residuals(p, poses)
    cost = sum(x * x for x in r)
    damping = 1e-3
    for _ in range(iterations):
        columns = []
        for k in range(PARAMS):
            step = 1e-7
            moved = list(p)
            moved[k] += step
            behind = list(p)
            behind[k] -= step
            ahead_r, behind_r = residuals(moved, poses), residuals(behind, poses)
            columns.append([(ahead_r[i] - behind_r[i]) / (2 * step) for i in range(len(r))])
        jtj = [[sum(ci * cj for ci, cj in zip(columns[a], columns[b])) for b in range(PARAMS)] for a in range(PARAMS)]
        jtr = [sum(c * x for c, x in zip(columns[a], r)) for a in range(PARAMS)]
        improved = False
        while damping < 1e12:
            system = [[jtj[a][b] + (damping * (jtj[a][a] + 1e-12) if a == b else 0.0) for b in range(PARAMS)]
                      for a in range(PARAMS)]
            delta = solve(system, [-x for x in jtr])
            if delta is not None:
                trial = [pi + di for pi, di in zip(p, delta)]
                trial_r = residuals(trial, poses)
                trial_cost = sum(x * x for x in trial_r)
                if trial_cost < cost:
                    converged = cost - trial_cost <= 1e-13 * cost
                    p, r, cost = trial, trial_r, trial_cost
                    damping = max(damping / 10.0, 1e-12)
                    improved = True
                    break
            damping *= 10.0
        if not improved or converged:
            break
    return p, cost


def main():
    grid_path, result_path = sys.argv[1], sys.argv[2]
    starts = int(sys.argv[3]) if len(sys.argv) > 3 else 4
    rows = []
    with open(grid_path) as f:
        for row in csv.DictReader(f):
            measured = [(float(row[c + '_t']) + float(row[c + '_dif'])) * 1e-3 for c in 'xyz']
            q = [math.radians(float(row['joint_%d' % (j + 1)])) for j in range(JOINTS)]
            rows.append((q, measured))
    result = json.load(open(result_path))
    test_of = {}
    for s in result['report']['samples']:
        test_of[tuple(round(v, 7) for v in s['measured_m'])] = s['test']
    train = [r for r in rows if not test_of[tuple(round(v, 7) for v in r[1])]]
    test = [r for r in rows if test_of[tuple(round(v, 7) for v in r[1])]]
    nominal = []
    for j in range(JOINTS):
        nominal += [0.0, D_M[j], A_M[j], ALPHA_RAD[j]]
    nominal += TOOL_M + [0.0] * 6
    generator = random.Random(53)
    best = None
    for k in range(starts):
        start = list(nominal)
        if k > 0:  # 5 mm, 5 mrad, 5 mm / 5 mrad of base off the nominal
            start = [v + generator.uniform(-5e-3, 5e-3) for v in nominal]
        p, cost = fit(start, train)
        rms_mm = math.sqrt(cost / len(train)) * 1e3
        print('start %d: training RMS %.6f mm' % (k, rms_mm), flush=True)
        if best is None or cost < best[1]:
            best = (p, cost)
    p = best[0]
    errors = [math.dist(predict(p, q), m) for q, m in test]
    train_errors = [math.dist(predict(p, q), m) for q, m in train]
    print('reference least squares: %d training poses MAE %.4f mm, %d test poses MAE %.4f mm' %
          (len(train), 1e3 * sum(train_errors) / len(train), len(test), 1e3 * sum(errors) / len(errors)))
    print('hivecal result: test MAE %.4f mm' % (1e3 * result['metrics']['test']['mae_m']['3d']))


if __name__ == '__main__':
    main()
