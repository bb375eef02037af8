"""The table of run.sh: each renderer's RMSE against pbrt-v3's 4096-sample image of the crop window around the
Cornell box's emitter, written as its share of a 256×256 image's RMSE (√(Σ error² / 65536 pixels), channels
averaged), so it compares with the "RMSE share of light + border" column of experiments/results/irc-peer/peer.md."""
import math
import struct
import sys

WINDOW = (96, 14, 64, 14)  # x0, y0 (from the top), width, height on the 256×256 film


def read_pfm(path):
    with open(path, "rb") as f:
        assert f.readline().strip() == b"PF", path
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        data = f.read()
    fmt = ("<" if scale < 0 else ">") + "%df" % (3 * w * h)
    v = struct.unpack(fmt, data[: 12 * w * h])
    # PFM rows run bottom to top; return rows top to bottom as lists of RGB triples.
    rows = [[v[3 * (y * w + x): 3 * (y * w + x) + 3] for x in range(w)] for y in range(h)]
    return w, h, rows[::-1]


def window(path):
    w, h, rows = read_pfm(path)
    x0, y0, ww, hh = WINDOW
    if (w, h) == (ww, hh):  # a cropped image
        return [p for r in rows for p in r]
    return [p for r in rows[y0:y0 + hh] for p in r[x0:x0 + ww]]


def share(img, truth):
    se = sum(sum((a - b) ** 2 for a, b in zip(p, q)) / 3 for p, q in zip(img, truth))
    return math.sqrt(se / (256 * 256))


def row(name, values):
    n = len(values)
    mean = sum(values) / n
    sd = math.sqrt(sum((v - mean) ** 2 for v in values) / (n - 1)) if n > 1 else 0.0
    spread = f"{sd:.5f}" if n > 1 else "–"
    print(f"| {name} | {n} | {mean:.5f} | {spread} | {min(values):.5f} | {max(values):.5f} |")


def main(out):
    truth = window(f"{out}/truth.pfm")
    print("| renderer (lowdiscrepancy, 64 samples) | runs | mean | sd | min | max |")
    print("|---|---|---|---|---|---|")
    row("cachert, seeds 0–31", [share(window(f"{out}/cachert-{s}.pfm"), truth) for s in range(32)])
    row("pbrt-v2, --ncores 1–256", [share(window(f"{out}/v2-{n}.pfm"), truth) for n in (1, 2, 4, 8, 16, 32, 64, 128, 256)])
    row("pbrt-v3 (no seed)", [share(window(f"{out}/v3.pfm"), truth)])
    row("cachert at 4096 samples, seeds 0–1 (the truth's own noise and any bias)",
        [share(window(f"{out}/cachert-4096-{s}.pfm"), truth) for s in (0, 1)])


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "/tmp/cachert-edge-noise")
