"""Stixel overlays drawn the way pyStixel-lib's draw_stixels_on_image does, with
Pillow (python3-pil) for the drawing and compositing and matplotlib's colormap
lookup tables rebuilt in numpy (matplotlib itself is not needed):
stixels sorted far to near, confidence >= prob, rectangle (u - w//2, vT) to
(u + w//2, vB) clipped to the image, colour RdYlGn((d - 5) / 45) or
jet(cluster / clusters), fill alpha int(alpha * 255) on a transparent RGBA
layer, then Image.alpha_composite onto the picture."""
import sys

import stixel_refutil as ru

np = ru.import_numpy()
try:
    from PIL import Image, ImageDraw
except ImportError as e:
    sys.exit("error: the overlay reference needs Pillow for /usr/bin/python3: "
             "apt-get install -y python3-pil (%s)" % e)

N = 256
RDYLGN = [(165, 0, 38), (215, 48, 39), (244, 109, 67), (253, 174, 97), (254, 224, 139), (255, 255, 191),
          (217, 239, 139), (166, 217, 106), (102, 189, 99), (26, 152, 80), (0, 104, 55)]
JET = {"red": [(0., 0, 0), (0.35, 0, 0), (0.66, 1, 1), (0.89, 1, 1), (1, 0.5, 0.5)],
       "green": [(0., 0, 0), (0.125, 0, 0), (0.375, 1, 1), (0.64, 1, 1), (0.91, 0, 0), (1, 0, 0)],
       "blue": [(0., 0.5, 0.5), (0.11, 1, 1), (0.34, 1, 1), (0.65, 0, 0), (1, 0, 0)]}


def lookup_table(nodes):
    """matplotlib.colors._create_lookup_table(N, nodes, gamma=1)."""
    a = np.array(nodes, dtype=float)
    x, y0, y1 = a[:, 0] * (N - 1), a[:, 1], a[:, 2]
    xind = (N - 1) * np.linspace(0, 1, N) ** 1.0
    ind = np.searchsorted(x, xind)[1:-1]
    dist = (xind[1:-1] - x[ind - 1]) / (x[ind] - x[ind - 1])
    return np.clip(np.concatenate([[y1[0]], dist * (y0[ind] - y1[ind - 1]) + y1[ind - 1], [y0[-1]]]), 0, 1)


def rdylgn_lut():
    vals = np.linspace(0, 1, len(RDYLGN))
    return np.stack([lookup_table([(x, c[k] / 255, c[k] / 255) for x, c in zip(vals, RDYLGN)])
                     for k in range(3)], 1)


def colormap(lut, x):
    """Colormap.__call__ on a Python float, then int(c * 255)."""
    xa = x * N
    if xa == N:
        xa = N - 1
    if np.isnan(xa):
        return (0, 0, 0)
    i = 0 if xa < 0 else (N - 1 if xa >= N else int(xa))
    return tuple(int(c * 255) for c in lut[i])


def draw(img, stixels, clusters, alpha, prob, instances, luts):
    image = img.convert("RGBA")
    overlay = Image.new("RGBA", image.size, (0, 0, 0, 0))
    d = ImageDraw.Draw(overlay)
    for s in sorted(stixels, key=lambda s: s["d"], reverse=True):
        if not float(s["confidence"]) >= prob:
            continue
        off = s["width"] // 2
        tl = (int(s["u"] - off), int(s["vT"]))
        br = (int(s["u"] + off), int(s["vB"]))
        left, right = max(0, min(tl[0], br[0])), min(image.width - 1, max(tl[0], br[0]))
        top, bottom = max(0, min(tl[1], br[1])), min(image.height - 1, max(tl[1], br[1]))
        if right <= left or bottom <= top:
            continue
        if instances:
            color = colormap(luts["jet"], s["cluster"] / clusters)
        else:
            color = colormap(luts["rdylgn"], (s["d"] - 5.0) / (50.0 - 5.0))
        d.rectangle([left, top, right, bottom], fill=color + (int(alpha * 255),))
    return np.array(Image.alpha_composite(image, overlay).convert("RGB"))


def bev_points(K, us, vs, ds):
    """pyStixel-lib's convert_to_3d_stixel: float32 [u, v, d, 1] rows, u and v
    times d in float32, inverse(K4) in float64 (T = I). Its bottom points
    (_project_uvd_to_xyz) use a float32 inverse; both use float64 here, as ours."""
    m = np.ones((len(us), 4), dtype=np.float32)
    m[:, 0], m[:, 1], m[:, 2] = us, vs, ds
    m[:, :2] *= m[:, 2:3]
    k = np.eye(4)
    k[:3, :3] = np.array(K, dtype=np.float32).astype(np.float64).reshape(3, 3)
    return (np.linalg.inv(k) @ m.T).T[:, :3]


def draw_bev(stixels, K, size, alpha, prob, coloring, luts):
    """pyStixel-lib's draw_stixels_birds_eye_view (x/z plane), with Pillow."""
    width, height = size
    sel = [i for i, s in enumerate(stixels) if float(s["confidence"]) >= float(prob)]
    us = [s["u"] for s in stixels]
    top = bev_points(K, us, [s["vT"] for s in stixels], [s["d"] for s in stixels])[sel][:, [0, 2]]
    bottom = bev_points(K, us, [s["vB"] for s in stixels], [s["d"] for s in stixels])[sel][:, [0, 2]]
    x_all = np.concatenate([top[:, 0], bottom[:, 0]])
    z_all = np.concatenate([top[:, 1], bottom[:, 1]])
    x_min, x_max = float(np.nanmin(x_all)), float(np.nanmax(x_all))
    z_min, z_max = float(np.nanmin(z_all)), float(np.nanmax(z_all))

    def to_px(x, z):
        xn = (x - x_min) / (x_max - x_min)
        zn = (z - z_min) / (z_max - z_min)
        return (int(np.clip(xn * (width - 1), 0, width - 1)), int(np.clip((1.0 - zn) * (height - 1), 0, height - 1)))

    image = Image.new("RGBA", (width, height), (20, 20, 20, 255))
    overlay = Image.new("RGBA", (width, height), (0, 0, 0, 0))
    d = ImageDraw.Draw(overlay)
    valid = [stixels[i]["cluster"] for i in sel if stixels[i]["cluster"] >= 0]
    max_cluster = max(valid) if valid else 1
    for k, i in enumerate(sel):
        s = stixels[i]
        if coloring == "cluster":
            cid = s["cluster"]
            if cid < 0:
                rgb = (0.5, 0.5, 0.5)
            else:
                denom = max(1, max_cluster)
                t = float(cid % (denom + 1)) / float(denom)
                rgb = (t, 1.0 - abs(2.0 * t - 1.0), 1.0 - t)
            color = tuple(int(c * 255) for c in rgb)
        elif coloring == "confidence":
            conf = float(np.clip(s["confidence"], 0.0, 1.0))
            color = (int((1.0 - conf) * 255.0), int(conf * 255.0), 0)
        else:
            color = colormap(luts["rdylgn"], (s["d"] - 5.0) / (50.0 - 5.0))
        pt, pb = to_px(*top[k]), to_px(*bottom[k])
        d.line((pt[0], pt[1], pb[0], pb[1]), fill=color + (int(alpha * 255),), width=2)
        d.ellipse((pb[0] - 1, pb[1] - 1, pb[0] + 1, pb[1] + 1), fill=color + (255,))
    return np.array(Image.alpha_composite(image, overlay).convert("RGB"))


def main(argv):
    a = ru.args(argv)
    rng = np.random.default_rng(21)
    W, H, n = 320, 200, 300
    bg = rng.integers(0, 256, (H, W, 3), dtype=np.uint8)
    u = rng.integers(-10, W + 10, n).astype(np.int32)
    vT = rng.integers(-20, H + 20, n).astype(np.int32)
    vB = (vT + rng.integers(-30, 90, n)).astype(np.int32)
    d = rng.uniform(0.0, 70.0, n).astype(np.float32)
    d[:20] = np.float32(rng.uniform(10, 12))  # ties: the sort must be stable
    width = rng.choice([8, 16, 5, 0, 1], n).astype(np.int32)
    conf = rng.random(n, dtype=np.float32)
    cluster = rng.integers(-1, 9, n).astype(np.int32)
    clusters = 8
    stixels = [dict(u=int(u[i]), vT=int(vT[i]), vB=int(vB[i]), d=float(d[i]), width=int(width[i]),
                    confidence=float(conf[i]), cluster=int(cluster[i])) for i in range(n)]
    luts = {"rdylgn": rdylgn_lut(),
            "jet": np.stack([lookup_table(JET[c]) for c in ("red", "green", "blue")], 1)}
    img = Image.fromarray(bg, "RGB")
    ru.save(a.out + "/stixel_render.safetensors", {
        "background": bg, "u": u, "vT": vT, "vB": vB, "d": d, "width": width, "confidence": conf,
        "cluster": cluster,
        "overlay_depth": draw(img, stixels, clusters, 0.5, 0.5, False, luts),
        "overlay_clusters": draw(img, stixels, clusters, 0.7, 0.2, True, luts),
    }, {"clusters": clusters})
    # Fitted bird's-eye views of an optical-frame world (standard K, T = I).
    m = 400
    K = [700.0, 0.0, 320.0, 0.0, 700.0, 200.0, 0.0, 0.0, 1.0]
    bu = rng.integers(0, 640, m).astype(np.int32)
    bvT = rng.integers(0, 400, m).astype(np.int32)
    bvB = (bvT + rng.integers(-5, 120, m)).astype(np.int32)
    bd = rng.uniform(4.0, 60.0, m).astype(np.float32)
    bconf = rng.random(m, dtype=np.float32)
    bcluster = rng.integers(-1, 7, m).astype(np.int32)
    bst = [dict(u=int(bu[i]), vT=int(bvT[i]), vB=int(bvB[i]), d=float(bd[i]), width=8,
                confidence=float(bconf[i]), cluster=int(bcluster[i])) for i in range(m)]
    ru.save(a.out + "/stixel_bev_fitted.safetensors", {
        "K": np.array(K, dtype=np.float32), "u": bu, "vT": bvT, "vB": bvB, "d": bd,
        "width": np.full(m, 8, dtype=np.int32), "confidence": bconf, "cluster": bcluster,
        "bev_depth": draw_bev(bst, K, (300, 260), 0.9, 0.5, "depth", luts),
        "bev_cluster": draw_bev(bst, K, (300, 260), 0.9, 0.2, "cluster", luts),
        "bev_confidence": draw_bev(bst, K, (256, 256), 0.9, 0.0, "confidence", luts),
    })
    print("stixel overlay and bird's-eye-view references written")


if __name__ == "__main__":
    main(sys.argv[1:])
