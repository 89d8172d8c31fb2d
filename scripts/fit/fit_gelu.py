# Fits the piecewise polynomials for h(a) = 0.5*erfc(a/sqrt(2)) = Phi(-a), a = |x|, used by
# the vector GELU: gelu(x) = x * (x >= 0 ? 1 - h(a) : h(a)). [0, A) is cut into `nint` equal
# intervals; in interval i, with u = a*s - 0.5 - i in [-0.5, 0.5] (s = nint/A in float),
# h ~= sum_j c[j][i] * u^j. Weighted minimax (Lawson) of the GELU absolute error a*|dh|.
import numpy as np, mpmath as mp, sys
mp.mp.dps = 40
def h(a): return float(0.5*mp.erfc(mp.mpf(a)/mp.sqrt(2)))
def lawson(u, f, w, deg, iters=600):
    V = np.vander(u, deg+1, increasing=True)
    lw = np.ones_like(u)/len(u)
    for _ in range(iters):
        sw = np.sqrt(lw)*w
        c, *_ = np.linalg.lstsq(V*sw[:,None], f*sw, rcond=None)
        e = np.abs(V@c - f)*w
        lw = lw*e; lw /= lw.sum()
    return c
def lawson_basis(V, f, w, iters=600):
    lw = np.ones(len(f))/len(f)
    for _ in range(iters):
        sw = np.sqrt(lw)*w
        c, *_ = np.linalg.lstsq(V*sw[:,None], f*sw, rcond=None)
        e = np.abs(V@c - f)*w
        lw = lw*e; lw /= lw.sum()
    return c
def fit(nint, deg, A=6.0):
    s = float(np.float32(nint/A))
    C = np.zeros((deg+1, nint), dtype=np.float32)
    worst = 0
    for i in range(nint):
        u = np.linspace(-0.5, 0.5, 801)
        a = (u + 0.5 + i)/s
        f = np.array([h(x) for x in a])
        w = np.maximum(a, 0.25)
        c = lawson(u, f, w, deg)
        # Round to float one coefficient at a time (lowest first), re-fitting the others
        # by weighted minimax, so the rounding costs little accuracy.
        V = np.vander(u, deg+1, increasing=True)
        for j in range(deg+1):
            C[j, i] = np.float32(c[j])
            if j < deg:
                r = f - V[:, :j+1] @ C[:j+1, i].astype(np.float64)
                cc = lawson_basis(V[:, j+1:], r, w)
                c = np.concatenate([C[:j+1, i].astype(np.float64), cc])
        e = (np.abs(np.vander(u, deg+1, increasing=True) @ C[:, i].astype(np.float64) - f)*w).max()
        worst = max(worst, e)
    return s, C, worst
import sys
for name, nint, deg in [(sys.argv[1], int(sys.argv[2]), int(sys.argv[3]))]:
    s, C, worst = fit(nint, deg)
    print(f"// {name}: {nint} intervals on [0, 6), degree {deg}, weighted max error {worst:.3g}")
    for j in range(deg+1):
        vals = ", ".join(f"{float(v):.9g}f" for v in C[j])
        print(f"  {{{vals}}},")
