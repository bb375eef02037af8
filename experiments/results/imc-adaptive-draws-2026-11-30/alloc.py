# The gain in MSE that allocating draws per pixel in proportion to sqrt(variance) could give at most, with the
# variance estimated from two seeds' squared errors smoothed over a k x k box: mean(V) / mean(sqrt V)^2.
import struct, sys, math
def pfm(p):
    f = open(p, 'rb'); assert f.readline().strip() == b'PF'
    w, h = map(int, f.readline().split()); s = float(f.readline())
    data = struct.unpack(('<' if s < 0 else '>') + 'f' * (w * h * 3), f.read(w * h * 12))
    return w, h, [sum(data[3*i+c]**2 for c in range(3)) / 3 for i in range(w * h)]
w, h, a = pfm(sys.argv[1]); _, _, b = pfm(sys.argv[2])
e = [(x + y) / 2 for x, y in zip(a, b)]
# integral image for box sums
I = [[0.0] * (w + 1) for _ in range(h + 1)]
for y in range(h):
    row = 0.0
    for x in range(w):
        row += e[y * w + x]; I[y + 1][x + 1] = I[y][x + 1] + row
for k in [1, 3, 7, 15, 31]:
    r = k // 2; V = []
    for y in range(h):
        y0, y1 = max(0, y - r), min(h, y + r + 1)
        for x in range(w):
            x0, x1 = max(0, x - r), min(w, x + r + 1)
            V.append((I[y1][x1] - I[y0][x1] - I[y1][x0] + I[y0][x0]) / ((y1 - y0) * (x1 - x0)))
    m = sum(V) / len(V); s = sum(math.sqrt(v) for v in V) / len(V)
    print(f"box {k:2d}: mean V {m:.3e}, mean(V)/mean(sqrt V)^2 = {m / s**2:.3f} (RMSE {math.sqrt(m / s**2):.3f})")
