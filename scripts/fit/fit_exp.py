# exp(r) ~= 1 + r + r^2 * P(r), P of degree 4, on |r| <= ln2/2 (minimax relative error).
import numpy as np, mpmath as mp
mp.mp.dps = 40
L = float(mp.log(2)/2) * 1.001
r = np.linspace(-L, L, 4001)
e = np.array([float(mp.exp(x)) for x in r])
f = np.array([float((mp.exp(x) - 1 - x)/(x*x)) if abs(x) > 1e-12 else 0.5 for x in r])
w = r*r/e
V = np.vander(r, 5, increasing=True)
lw = np.ones_like(r)/len(r)
for _ in range(2000):
    sw = np.sqrt(lw)*w
    c, *_ = np.linalg.lstsq(V*sw[:,None], f*sw, rcond=None)
    err = np.abs(V@c - f)*w
    lw = lw*err; lw /= lw.sum()
print("rel err", (np.abs(V@c-f)*w).max())
c32 = c.astype(np.float32)
print("rel err f32 coeffs", (np.abs(V@c32.astype(np.float64)-f)*w).max())
print(", ".join(f"{float(v):.9g}f" for v in c32))
import struct
ln2 = mp.log(2)
hi = np.float32(float(ln2));
# hi with trailing bits cleared so n*hi is exact for |n| < 2^9
bits = struct.unpack('<I', struct.pack('<f', float(ln2)))[0] & 0xFFFFF000
hi = struct.unpack('<f', struct.pack('<I', bits))[0]
lo = np.float32(float(ln2 - hi))
print(f"ln2_hi {hi:.9g}f ln2_lo {float(lo):.9g}f log2e {float(np.float32(float(1/ln2))):.9g}f")
