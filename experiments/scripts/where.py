#!/usr/bin/env python3
"""Where the error of each placement sits, for one cell of the stability sweeps (issue 13: "explain why").

  python3 experiments/scripts/where.py NAME SCENE.pbrt WxH CACHES [--integrator cacheao] [--set k=v ...]

The one Python script of the repository (issue 40 kept it rather than port it): it needs only python3's
standard library and a built `target/release/cachert` (or $CACHERT). It is not Rust because it is an analysis
run by hand a few times, not part of the renderer or of `cachert experiment`: it renders with `cachert render`
and `cachert compare`, then reads the PFM images and cache overlays back to split the error into edge and
non-edge pixels and to measure the gaps between caches (a breadth-first distance transform), none of which the
experiment tables need. Findings: experiments/notes/stability.md; outputs: experiments/results/stability-where/.

Renders the per-sample reference (`none`) and each of im, sd, sd+as, vgc, vgc+dgs (seed 0) with cachert,
writing the images, cache overlays (PNG) and squared-error maps (PNG, `cachert compare --diff-map`) to
experiments/results/stability-where/NAME/, and prints and writes where.csv there: per placement, the RMSE over
all pixels, over the *edge* pixels (the 10 % of pixels where the reference changes most from a 4-neighbour:
silhouettes, creases, contact shadows) and over the rest, the share of the squared error that lies on the
edges, and the cache density (caches per pixel) on the edges and off them. The PFMs stay in $TMPDIR.
"""
import csv
import os
import struct
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
OUT = os.path.join(ROOT, "experiments", "results", "stability-where")
B = os.environ.get("CACHERT", os.path.join(ROOT, "target/release/cachert"))
PLACEMENTS = ["im", "sd", "sd+as", "vgc", "vgc+dgs"]
STAGE1 = (1.0, 0.1, 0.05)
STAGE2 = (0.0, 0.9, 1.0)


def read_pfm(path):
    with open(path, "rb") as f:
        kind = f.readline().strip()
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        n = w * h * (3 if kind == b"PF" else 1)
        data = struct.unpack(("<" if scale < 0 else ">") + f"{n}f", f.read(4 * n))
    px = [tuple(data[3 * i:3 * i + 3]) for i in range(w * h)]
    # PFM rows run bottom to top.
    rows = [px[(h - 1 - y) * w:(h - y) * w] for y in range(h)]
    return w, h, [p for r in rows for p in r]


def lum(p):
    return (p[0] + p[1] + p[2]) / 3.0


def render(scene, res, integrator, extra, out, placement, caches, overlay=None):
    cmd = [B, "render", scene, "--integrator", integrator, "--resolution", res, "--placement", placement,
           "--caches", str(caches), "--quiet", "--outfile", out] + extra
    if overlay:
        cmd += ["--overlay", overlay]
    subprocess.run(cmd, check=True, stderr=subprocess.DEVNULL)


def main():
    args = sys.argv[1:]
    name, scene, res, caches = args[0], args[1], args[2], int(args[3])
    integrator, extra = "cacheao", []
    i = 4
    while i < len(args):
        if args[i] == "--integrator":
            integrator = args[i + 1]
        else:
            extra += [args[i], args[i + 1]]
        i += 2
    out = os.path.join(OUT, name)
    tmp = os.path.join(os.environ.get("TMPDIR", "/tmp"), "cachert-where-" + name)
    os.makedirs(out, exist_ok=True)
    os.makedirs(tmp, exist_ok=True)
    ref = os.path.join(tmp, "none.pfm")
    if not os.path.exists(ref):
        render(scene, res, integrator, extra, ref, "none", caches)
    w, h, r = read_pfm(ref)
    rl = [lum(p) for p in r]
    # Edge pixels: the 10 % with the largest change of the reference to a 4-neighbour.
    grad = []
    for y in range(h):
        for x in range(w):
            v = rl[y * w + x]
            d = 0.0
            for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                if 0 <= x + dx < w and 0 <= y + dy < h:
                    d = max(d, abs(rl[(y + dy) * w + x + dx] - v))
            grad.append(d)
    cut = sorted(grad)[int(0.9 * len(grad))]
    edge = [g > cut for g in grad]
    n_edge = sum(edge)
    rows = []
    for p in PLACEMENTS:
        tag = p.replace("+", "_")
        img, ov = os.path.join(tmp, f"{tag}.pfm"), os.path.join(tmp, f"{tag}-overlay.pfm")
        render(scene, res, integrator, extra, img, p, caches, ov)
        subprocess.run([B, "render", scene, "--integrator", integrator, "--resolution", res, "--placement", p,
                        "--caches", str(caches), "--quiet", "--outfile", os.path.join(tmp, "x.pfm"),
                        "--overlay", os.path.join(out, f"{tag}-overlay.png")] + extra,
                       check=True, stderr=subprocess.DEVNULL)
        subprocess.run([B, "compare", img, ref, "--diff-map", os.path.join(out, f"{tag}-error.png")],
                       check=True, stdout=subprocess.DEVNULL)
        _, _, t = read_pfm(img)
        _, _, o = read_pfm(ov)
        sq = [sum((a - b) ** 2 for a, b in zip(t[i], r[i])) / 3.0 for i in range(w * h)]
        sites = [any(max(abs(a - b) for a, b in zip(o[i], c)) < 1e-6 for c in (STAGE1, STAGE2)) for i in range(w * h)]
        # Distance in pixels from every pixel to its nearest cache (multi-source breadth-first search,
        # 8-neighbour steps), and its 95th percentile off the edges: how large the gaps between caches are.
        dist = [-1] * (w * h)
        queue = [i for i in range(w * h) if sites[i]]
        for i in queue:
            dist[i] = 0
        head = 0
        while head < len(queue):
            i = queue[head]
            head += 1
            x, y = i % w, i // w
            for dx in (-1, 0, 1):
                for dy in (-1, 0, 1):
                    if (dx or dy) and 0 <= x + dx < w and 0 <= y + dy < h and dist[(y + dy) * w + x + dx] < 0:
                        dist[(y + dy) * w + x + dx] = dist[i] + 1
                        queue.append((y + dy) * w + x + dx)
        rest_d = sorted(d for d, e in zip(dist, edge) if not e)
        se_edge = sum(s for s, e in zip(sq, edge) if e)
        se_all = sum(sq)
        c_edge = sum(1 for s, e in zip(sites, edge) if s and e)
        c_all = sum(sites)
        rows.append({
            "placement": p, "caches": c_all,
            "rmse": f"{(se_all / (w * h)) ** 0.5:.5f}",
            "rmse_edges": f"{(se_edge / n_edge) ** 0.5:.5f}",
            "rmse_rest": f"{((se_all - se_edge) / (w * h - n_edge)) ** 0.5:.5f}",
            "error_share_on_edges": f"{se_edge / se_all:.3f}",
            "cache_density_edges": f"{c_edge / n_edge:.4f}",
            "cache_density_rest": f"{(c_all - c_edge) / (w * h - n_edge):.4f}",
            "gap_rest_mean_px": f"{sum(rest_d) / len(rest_d):.2f}",
            "gap_rest_p95_px": rest_d[int(0.95 * len(rest_d))],
        })
    with open(os.path.join(out, "where.csv"), "w", newline="") as f:
        wr = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        wr.writeheader()
        wr.writerows(rows)
    print(f"{name}: {w}x{h}, {caches} caches, {n_edge} edge pixels (reference change > {cut:.4g})")
    for row in rows:
        print("  " + ", ".join(f"{k} {v}" for k, v in row.items()))


if __name__ == "__main__":
    main()
