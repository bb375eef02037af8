"""How much faster importance caching would have to run, with the same images, to be 2x ahead of the better
many-light baseline at equal time; and the baseline's local slope d ln RMSE / d ln t there.
For the equal-time folders on the command line, as ratios.py reads them (the caches' mean wall seconds and mean
RMSE over seeds; each baseline's means over seeds, interpolated linearly in log-time/log-error between its two
nearest sample counts, extrapolated as error ~ t^-1/2 outside them). A bit-identical speed-up leaves the caches'
RMSE e as it is, so the goal needs the time t' at which the better baseline's RMSE is 2e: the speed-up is t / t'.
Usage: python3 speedup.py FOLDER...   (prints scene, caches, better baseline, ratio, slope, speed-up needed)"""
import collections
import csv
import math
import sys


def curve(pts, t):
    """The baseline's log-log interpolated RMSE at time t, and the local slope used."""
    if t < pts[0][0]:
        return pts[0][1] * math.sqrt(pts[0][0] / t), -0.5
    if t > pts[-1][0]:
        return pts[-1][1] * math.sqrt(pts[-1][0] / t), -0.5
    i = max(0, min(len(pts) - 2, sum(1 for p in pts if p[0] <= t) - 1))
    (t0, e0), (t1, e1) = pts[i], pts[i + 1]
    s = (math.log(e1) - math.log(e0)) / (math.log(t1) - math.log(t0))
    return math.exp(math.log(e0) + s * (math.log(t) - math.log(t0))), s


def time_at(pts, e):
    """The time at which the baseline's RMSE is e (bisection on log t; the curve falls with t)."""
    lo, hi = math.log(pts[0][0]) - 5, math.log(pts[-1][0]) + 5
    for _ in range(200):
        mid = (lo + hi) / 2
        if curve(pts, math.exp(mid))[0] > e:
            lo = mid
        else:
            hi = mid
    return math.exp((lo + hi) / 2)


for run in sys.argv[1:]:
    rows = [r for r in csv.DictReader(open(run + '/results.csv')) if r['status'] == 'ok']
    caches, base = collections.defaultdict(list), collections.defaultdict(list)
    for r in rows:
        m = r['method'].split(':')[0]
        if r['placement'] == 'vgc+dgs':
            caches[(r['scene'], int(r['caches']))].append((float(r['total_s']), float(r['rmse'])))
        elif m in ('uniform', 'power'):
            base[(r['scene'], m, int(r['samples']))].append((float(r['total_s']), float(r['rmse'])))
    print(run.rstrip('/').split('/')[-1])
    for (sc, k), v in sorted(caches.items()):
        t = sum(x[0] for x in v) / len(v)
        e = sum(x[1] for x in v) / len(v)
        best = None
        for m in ('uniform', 'power'):
            pts = sorted((sum(x[0] for x in b) / len(b), sum(x[1] for x in b) / len(b))
                         for (s2, m2, n), b in base.items() if s2 == sc and m2 == m)
            if len(pts) < 2:
                continue
            eb, slope = curve(pts, t)
            if best is None or eb / e < best[1]:
                best = (m, eb / e, slope, t / time_at(pts, 2 * e))
        m, ratio, slope, need = best
        print(f"{sc} {k} {m} ratio {ratio:.4f} slope {slope:.3f} speed-up needed {need:.3f}")
