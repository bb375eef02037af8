#!/usr/bin/env python3
"""Mean ± sd tables over seeds from a `cachert experiment` results.csv, one per scene, as in tables.md.
Standard library only.  Usage: tables.py results.csv"""
import csv, sys, statistics as st
from collections import defaultdict
rows = list(csv.DictReader(open(sys.argv[1])))
g = defaultdict(list)
order = []
for r in rows:
    # The reference, and the per-pixel baselines' rows (`power:N`, one seed, no caches: equal_time.py's).
    if r["placement"] == "none" or int(r["caches"]) == 0: continue
    k = (r["scene"], int(r["caches"]), r["placement"])
    if k not in g: order.append(k)
    g[k].append(r)
scenes = list(dict.fromkeys(k[0] for k in order))
for sc in scenes:
    print(f"\n{sc} (mean ± sd over seeds; total s = mean wall of the whole render)\n")
    print("| caches | placement | RMSE | HDR-FLIP | total s | cache eval s |\n|---|---|---|---|---|---|")
    for k in sorted((k for k in order if k[0] == sc), key=lambda k: (k[1], order.index(k))):
        rs = g[k]; e = [float(r["rmse"]) for r in rs]; f = [float(r["flip"]) for r in rs]
        t = st.mean(float(r["total_s"]) for r in rs)
        ce = st.mean(float(r["initial_comp_s"]) + float(r["adaptive_comp_s"]) for r in rs)
        print(f"| {k[1]} | {k[2]} | {st.mean(e):.5f} ± {st.stdev(e):.5f} | {st.mean(f):.4f} ± {st.stdev(f):.4f} | {t:.1f} | {ce:.1f} |")
