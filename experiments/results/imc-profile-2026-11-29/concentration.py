"""Share of an image's squared error (against a reference) held by its worst pixels.

python3 concentration.py IMAGE.pfm REFERENCE.pfm  (both from `cachert convert X.exr X.pfm`)
Prints the RMSE over every pixel and channel, then for each fraction of the pixels, worst first, the share of
the total squared error they hold (a pixel's squared error: the mean over its three channels).
"""
import struct
import sys


def read(path):
    with open(path, "rb") as f:
        f.readline()
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        n = w * h * 3
        return w, h, struct.unpack(("<" if scale < 0 else ">") + "%df" % n, f.read(4 * n))


w, h, a = read(sys.argv[1])
_, _, b = read(sys.argv[2])
err = sorted((sum((a[3 * i + c] - b[3 * i + c]) ** 2 for c in range(3)) / 3 for i in range(w * h)), reverse=True)
total = sum(err)
print("rmse %.6f" % (total / (w * h)) ** 0.5)
for frac in (0.001, 0.01, 0.05, 0.1, 0.25):
    k = max(1, int(frac * w * h))
    print("worst %g of the pixels: %.3f of the squared error" % (frac, sum(err[:k]) / total))
