#!/usr/bin/env python3
"""Builds the stability CSVs of issue 13 from the per-run results.csv files that run.sh copied to runs/.

  failure-map.csv     one row per application x scene x resolution x budget x placement: RMSE and HDR-FLIP
                      (mean and standard deviation over seeds), the ratio to IM's, whether the placement is
                      significantly worse than IM (difference of means > 2 standard errors), and the cell's
                      best placement by each metric.
  seed-stability.csv  the same runs as spread over seeds: coefficient of variation of RMSE and FLIP, flagged
                      when the standard deviation exceeds 10 % of the mean.
  sensitivity.csv     SD's minimum cluster size and VGC's sigma_a (Fig. 8): error and cache count per value.

Only the Python standard library; run from anywhere: python3 results/stability/aggregate.py
"""
import csv
import glob
import math
import os
import re
import statistics

HERE = os.path.dirname(os.path.abspath(__file__))
PAPER = {"cacheao": 120000, "irradiancecache": 40000, "importancecache": 25000}


def stats(values):
    m = statistics.fmean(values)
    s = statistics.stdev(values) if len(values) > 1 else 0.0
    return m, s


def read_runs(pattern):
    """(tag fields, rows) per runs/<pattern>.csv."""
    out = []
    for path in sorted(glob.glob(os.path.join(HERE, "runs", pattern))):
        with open(path, newline="") as f:
            rows = [r for r in csv.DictReader(f) if r["placement"] != "none"]
        out.append((os.path.basename(path)[:-4], rows))
    return out


def groups(rows, key):
    g = {}
    for r in rows:
        g.setdefault(key(r), []).append(r)
    return g


def fmt(x):
    return f"{x:.6g}"


def failure_map():
    cells = []
    for tag, rows in read_runs("map-*.csv"):
        m = re.match(r"map-([a-z]+)-(.+)-(\d+x\d+)$", tag)
        app, scene, res = m.groups()
        w, h = map(int, res.split("x"))
        paper = PAPER[app] * w * h / (1920 * 1080)
        by_budget = groups(rows, lambda r: int(r["caches"]))
        for caches, rs in sorted(by_budget.items()):
            per = {}
            for p, prs in groups(rs, lambda r: r["placement"]).items():
                rm, rsd = stats([float(r["rmse"]) for r in prs])
                fm, fsd = stats([float(r["flip"]) for r in prs])
                tm, _ = stats([float(r["total_s"]) for r in prs])
                per[p] = dict(n=len(prs), rmse=rm, rmse_sd=rsd, flip=fm, flip_sd=fsd, secs=tm)
            best_r = min(per, key=lambda p: per[p]["rmse"])
            best_f = min(per, key=lambda p: per[p]["flip"])
            im = per.get("im")
            for p, s in per.items():
                def worse(metric):
                    if im is None or p == "im":
                        return ""
                    se = math.sqrt(s[metric + "_sd"] ** 2 / s["n"] + im[metric + "_sd"] ** 2 / im["n"])
                    d = s[metric] - im[metric]
                    return "worse" if d > 2 * se else ("better" if d < -2 * se else "tie")
                cells.append({
                    "application": app, "scene": scene, "resolution": res,
                    "density": fmt(caches / paper), "caches": caches, "placement": p, "seeds": s["n"],
                    "rmse_mean": fmt(s["rmse"]), "rmse_std": fmt(s["rmse_sd"]),
                    "flip_mean": fmt(s["flip"]), "flip_std": fmt(s["flip_sd"]),
                    "rmse_vs_im": fmt(s["rmse"] / im["rmse"]) if im else "",
                    "flip_vs_im": fmt(s["flip"] / im["flip"]) if im else "",
                    "rmse_vs_im_verdict": worse("rmse"), "flip_vs_im_verdict": worse("flip"),
                    "best_rmse": best_r, "best_flip": best_f, "secs_mean": fmt(s["secs"]),
                })
    write("failure-map.csv", cells)
    seeds = []
    for c in cells:
        r_cv = float(c["rmse_std"]) / float(c["rmse_mean"])
        f_cv = float(c["flip_std"]) / float(c["flip_mean"])
        seeds.append({k: c[k] for k in ("application", "scene", "resolution", "density", "caches", "placement",
                                         "seeds", "rmse_mean", "rmse_std", "flip_mean", "flip_std")}
                     | {"rmse_cv": fmt(r_cv), "flip_cv": fmt(f_cv),
                        "flagged": "yes" if max(r_cv, f_cv) > 0.10 else "no"})
    write("seed-stability.csv", seeds)
    return cells, seeds


def sensitivity():
    out = []
    for tag, rows in read_runs("sens-*.csv"):
        m = re.match(r"sens-([a-z]+)-(.+)-(sd|vgc)-([0-9.]+)$", tag)
        app, scene, method, value = m.groups()
        rm, rsd = stats([float(r["rmse"]) for r in rows])
        fm, fsd = stats([float(r["flip"]) for r in rows])
        placed = statistics.fmean(int(r["stage1"]) + int(r["stage2"]) for r in rows)
        out.append({"application": app, "scene": scene, "resolution": "320x180", "caches": rows[0]["caches"],
                    "method": method, "parameter": "sdminsize" if method == "sd" else "sigma_a",
                    "value": value, "seeds": len(rows), "rmse_mean": fmt(rm), "rmse_std": fmt(rsd),
                    "flip_mean": fmt(fm), "flip_std": fmt(fsd), "caches_placed": fmt(placed)})
    out.sort(key=lambda r: (r["application"], r["scene"], r["method"], float(r["value"])))
    write("sensitivity.csv", out)
    return out


def write(name, rows):
    if not rows:
        return
    with open(os.path.join(HERE, name), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    print(f"wrote {name}: {len(rows)} rows")


def markdown(cells, seeds, sens):
    """tables.md: the map as ratios to IM, the flagged seed spreads and the sensitivity sweeps."""
    mark = {"worse": " ▲", "better": " ▼", "tie": "", "": ""}
    out = ["# Stability tables (generated by aggregate.py from runs/; do not edit)", "",
           "## Where each placement loses to IM", "",
           "Mean RMSE and HDR-FLIP over the seeds, as a ratio to IM's in the same cell; ▲ significantly worse "
           "than IM (difference of means above 2 standard errors), ▼ significantly better. Density is the "
           "cache count over the paper's density for the application (120K, 40K, 25K caches at 1920×1080).", "",
           "| application | scene | resolution | density | caches | IM RMSE | IM FLIP | "
           "SD | SD+AS | VGC | VGC+DGS | best RMSE | best FLIP |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    cellmap = {}
    for c in cells:
        cellmap.setdefault((c["application"], c["scene"], c["resolution"], c["caches"]), {})[c["placement"]] = c
    for (app, scene, res, caches), c in cellmap.items():
        im = c["im"]
        def ratio(p):
            r = c[p]
            return (f"{float(r['rmse_vs_im']):.2f}{mark[r['rmse_vs_im_verdict']]} / "
                    f"{float(r['flip_vs_im']):.2f}{mark[r['flip_vs_im_verdict']]}")
        out.append(f"| {app} | {scene} | {res} | {float(im['density']):.1f} | {caches} | {float(im['rmse_mean']):.4f} | "
                   f"{float(im['flip_mean']):.4f} | " + " | ".join(ratio(p) for p in ("sd", "sd+as", "vgc", "vgc+dgs"))
                   + f" | {im['best_rmse']} | {im['best_flip']} |")
    out += ["", "Each ratio cell is RMSE / FLIP.", "", "## Seed stability", "",
            "Runs whose standard deviation over the seeds exceeds 10 % of the mean (RMSE or FLIP); every other "
            "run of seed-stability.csv is below.", "",
            "| application | scene | resolution | caches | placement | seeds | RMSE mean ± sd | FLIP mean ± sd |",
            "|---|---|---|---|---|---|---|---|"]
    for r in seeds:
        if r["flagged"] == "yes":
            out.append(f"| {r['application']} | {r['scene']} | {r['resolution']} | {r['caches']} | {r['placement']} | "
                       f"{r['seeds']} | {float(r['rmse_mean']):.4f} ± {float(r['rmse_std']):.4f} | "
                       f"{float(r['flip_mean']):.4f} ± {float(r['flip_std']):.4f} |")
    worst = max(seeds, key=lambda r: float(r["rmse_cv"]) if r["application"] == "cacheao" else 0)
    out += ["", f"Largest RMSE spread of cache AO: {float(worst['rmse_cv']):.3f} of the mean ({worst['scene']} "
            f"{worst['resolution']}, {worst['caches']} caches, {worst['placement']}).", "",
            "## Sensitivity (Fig. 8): SD's minimum cluster size and VGC's σ_a", "",
            "| application | scene | caches | method | value | RMSE mean ± sd | FLIP mean ± sd | caches placed |",
            "|---|---|---|---|---|---|---|---|"]
    for r in sens:
        out.append(f"| {r['application']} | {r['scene']} | {r['caches']} | {r['method']} | {r['parameter']} = "
                   f"{r['value']} | {float(r['rmse_mean']):.4f} ± {float(r['rmse_std']):.4f} | "
                   f"{float(r['flip_mean']):.4f} ± {float(r['flip_std']):.4f} | {r['caches_placed']} |")
    with open(os.path.join(HERE, "tables.md"), "w") as f:
        f.write("\n".join(out) + "\n")
    print("wrote tables.md")


if __name__ == "__main__":
    cells, seeds = failure_map()
    sens = sensitivity()
    markdown(cells, seeds, sens)
    # A short summary for the README.
    for c in cells:
        if c["rmse_vs_im_verdict"] == "worse" or c["flip_vs_im_verdict"] == "worse":
            print(f"loses to IM: {c['application']} {c['scene']} {c['resolution']} x{c['density']} "
                  f"{c['placement']}: RMSE {c['rmse_vs_im']} ({c['rmse_vs_im_verdict']}), "
                  f"FLIP {c['flip_vs_im']} ({c['flip_vs_im_verdict']})")
    for s in seeds:
        if s["flagged"] == "yes":
            print(f"seed spread > 10 %: {s['application']} {s['scene']} {s['resolution']} {s['caches']} "
                  f"{s['placement']}: RMSE cv {s['rmse_cv']}, FLIP cv {s['flip_cv']}")
