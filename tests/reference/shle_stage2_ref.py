"""Reference for SHLE stage 2 and the Kalman smoothing, in numpy only, following
the released code (github.com/Yang-Kaixing/SHLE, Stage2/post_process.py) as
described in ../shared/reference/shle.md:

  box y0 -= 20, y1 += 20, clipped to the image; rows int(y0)..int(y1)-1, columns
  int(x0)..int(x1)-1; Z = bf / d (d = raw / 32); Y = (v - cy) * Z / fy - mount;
  keep Y < -M; mode of sklearn's KernelDensity(kernel='gaussian', bandwidth=h) on
  linspace(0, int(max Z), int(max Z) + 1), first argmax of score_samples; keep
  mode - sigma < Z < mode + sigma; height = |mean| of the N largest Y.

sklearn's score_samples is re-derived here rather than imported: for a Gaussian
kernel with bandwidth h the log density at g is
  log( sum_i exp(-(g - z_i)^2 / (2 h^2)) ) - log(n) - log(h sqrt(2 pi)),
which sklearn evaluates exactly (atol = rtol = 0) with a log-sum-exp. Equal depths
are merged with their counts (log c_k added), which is the same sum.

Reads the synthetic sequences that shle_synth writes into OUT/shle_synth/ (a ctest
fixture) and writes OUT/shle_stage2.safetensors with, per scene and option set,
the per-frame heights (NaN = no height), KDE modes, point counts and the gap
between the best and second-best grid log density, plus the Kalman outputs.
"""
import json
import math
import os
import sys

try:
    import numpy as np
except ImportError as e:  # pragma: no cover
    sys.exit("error: the SHLE reference needs numpy for /usr/bin/python3: apt-get install -y python3-numpy (%s)" % e)

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "weights"))
import safetensors_io  # noqa: E402

# name -> stage-2 options; must match tests/shle/test_stage2_reference.cpp.
CONFIGS = [
    ("default", {}),
    ("ext0", {"ext_top": 0.0, "ext_bottom": 0.0}),
    ("nokde", {"use_kde": False}),
    ("nowindow", {"use_window": False}),
    ("n1", {"lowest_n": 1}),
    ("grid05", {"grid_step": 0.5}),
    ("bw1", {"bandwidth": 1.0}),
    ("m0", {"min_height": 0.0}),
]
MAX_DEPTH = 1e6  # depths beyond are invalid (shle/height.cpp)


def read_calib(path):
    with open(path) as f:
        c = json.load(f)
    bf = c["bf"] if "bf" in c else c["baseline"] * c["fx"]
    return dict(fx=c["fx"], fy=c["fy"], cx=c["cx"], cy=c["cy"], bf=bf,
                mount=c.get("mount_height", 1.45), width=c.get("width", 1280), height=c.get("height", 720))


def read_box(path):
    """First shape labelled 'height': the bounding box of its points."""
    if not os.path.exists(path):
        return None
    with open(path) as f:
        lm = json.load(f)
    for s in lm["shapes"]:
        if s["label"] == "height":
            p = np.array(s["points"], dtype=np.float64)
            return [p[:, 0].min(), p[:, 1].min(), p[:, 0].max(), p[:, 1].max()]
    return None


def read_dat(path, w, h):
    raw = np.fromfile(path, dtype="<u2")
    assert raw.size == w * h, path
    return raw.reshape(h, w).astype(np.float32) / np.float32(32.0)


def read_pfm(path):
    with open(path, "rb") as f:
        data = f.read()
    parts = data.split(b"\n", 3)
    assert parts[0] == b"Pf", path
    w, h = (int(t) for t in parts[1].split())
    scale = float(parts[2])
    arr = np.frombuffer(parts[3], dtype="<f4" if scale < 0 else ">f4", count=w * h)
    return arr.reshape(h, w)[::-1].astype(np.float32)


def sequence_frames(scene_dir):
    """(image stem, labelme path, disparity path, format) in file-name order."""
    out = []
    if os.path.isdir(os.path.join(scene_dir, "left_colorimages")):
        img_dir = os.path.join(scene_dir, "left_colorimages")
        for name in sorted(n for n in os.listdir(img_dir) if n.endswith(".png")):
            stem = name[:-4]
            fields = stem.split("_")
            disp = os.path.join(scene_dir, "disparity_images", "disparity_5_" + "_".join(fields[1:5]) + ".dat")
            out.append((stem, os.path.join(img_dir, stem + ".json"), disp, "dat"))
    else:
        img_dir = os.path.join(scene_dir, "left")
        for name in sorted(n for n in os.listdir(img_dir) if n.endswith(".png")):
            stem = name[:-4]
            for ext in ("dat", "pfm"):
                p = os.path.join(scene_dir, "disparity", stem + "." + ext)
                if os.path.exists(p):
                    out.append((stem, os.path.join(img_dir, stem + ".json"), p, ext))
                    break
    return out


def kde_mode(z, bandwidth, grid_step):
    """First argmax of the KDE log density on the grid 0, s, ..., floor(max z / s) s.
    Returns (mode, gap between the best and the second-best log density)."""
    values, counts = np.unique(z, return_counts=True)
    log_c = np.log(counts.astype(np.float64))
    if grid_step == 1.0:
        grid = np.linspace(0, int(z.max()), int(z.max()) + 1)  # the released grid
    else:
        grid = np.arange(0, math.floor(z.max() / grid_step) + 1, dtype=np.float64) * grid_step
    two_h2 = 2.0 * bandwidth * bandwidth
    log_norm = math.log(z.size) + math.log(bandwidth * math.sqrt(2.0 * math.pi))
    dens = np.empty(grid.size)
    for a in range(0, grid.size, 256):
        g = grid[a:a + 256, None]
        e = -((g - values[None, :]) ** 2) / two_h2 + log_c[None, :]
        top = e.max(axis=1)
        dens[a:a + 256] = top + np.log(np.exp(e - top[:, None]).sum(axis=1)) - log_norm
    best = int(np.argmax(dens))  # first maximum, as numpy and the released code
    rest = np.delete(dens, best)
    gap = float(dens[best] - rest.max()) if rest.size else math.inf
    return float(grid[best]), gap


def stage2(disp, box, cal, ext_top=20.0, ext_bottom=20.0, min_height=1.5, use_kde=True, bandwidth=2.5,
           grid_step=1.0, use_window=True, sigma=0.6, lowest_n=10):
    """(height or nan, mode or nan, points after the prefilter, window points, gap)."""
    H, W = disp.shape
    x0, y0, x1, y1 = box
    y0 -= ext_top
    y1 += ext_bottom
    x0, y0 = max(x0, 0.0), max(y0, 0.0)
    x1, y1 = min(x1, float(W)), min(y1, float(H))
    r0, r1, c0, c1 = int(y0), int(y1), int(x0), int(x1)
    if r1 <= r0 or c1 <= c0:
        return math.nan, math.nan, 0, 0, math.inf
    d = disp[r0:r1, c0:c1].astype(np.float64)
    v = np.arange(r0, r1, dtype=np.float64)[:, None] * np.ones((1, c1 - c0))
    with np.errstate(divide="ignore", invalid="ignore"):
        z = cal["bf"] / d
        y = (v - cal["cy"]) * z / cal["fy"] - cal["mount"]
    valid = (d > 0) & np.isfinite(d) & (z <= MAX_DEPTH)
    keep = valid & (y < -min_height)
    z, y = z[keep], y[keep]
    if z.size == 0:
        return math.nan, math.nan, 0, 0, math.inf
    gap = math.inf
    if use_kde:
        mode, gap = kde_mode(z, bandwidth, grid_step)
    else:
        mode = float(z.mean())
    sel = ((z > mode - sigma) & (z < mode + sigma)) if use_window else np.ones(z.size, dtype=bool)
    yw = y[sel]
    if yw.size == 0:
        return math.nan, mode, int(z.size), 0, gap
    lowest = np.sort(yw)[::-1][:lowest_n]  # largest Y = lowest points
    return abs(float(lowest.mean())), mode, int(z.size), int(yw.size), gap


def kalman(z, q=1e-3, r=1e-2, p0=6.0):
    """Aligned output x0..x(n-1) and the released off-by-one output."""
    out = []
    x, p = None, None
    for v in z:
        if x is None:
            x, p = v, p0
        else:
            p_pred = p + q
            k = p_pred / (p_pred + r)
            x = x + k * (v - x)
            p = (1.0 - k) * p_pred
        out.append(x)
    # Released: arrays of n + 1 entries, positions 1..n-1 filled, entries 1..n returned.
    compat = out[1:] + [0.0] if out else []
    return np.array(out, dtype=np.float64), np.array(compat, dtype=np.float64)


def main():
    import argparse
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    root = os.path.join(args.out, "shle_synth")
    scenes = sorted(n for n in os.listdir(root) if os.path.isdir(os.path.join(root, n)))
    if not scenes:
        sys.exit("error: no synthetic scenes in %s (the shle_synth fixture writes them)" % root)
    tensors = {}
    for scene in scenes:
        sdir = os.path.join(root, scene)
        cal = read_calib(os.path.join(sdir, "calib.json"))
        frames = sequence_frames(sdir)
        per = {name: ([], [], [], [], []) for name, _ in CONFIGS}
        for stem, lm, dpath, fmt in frames:
            box = read_box(lm)
            disp = read_dat(dpath, cal["width"], cal["height"]) if fmt == "dat" else read_pfm(dpath)
            for name, kw in CONFIGS:
                res = stage2(disp, box, cal, **kw) if box is not None else (math.nan, math.nan, 0, 0, math.inf)
                for lst, val in zip(per[name], res):
                    lst.append(val)
        for name, (h, mode, pts, win, gap) in per.items():
            key = "%s/%s/" % (scene, name)
            tensors[key + "height"] = np.array(h, dtype=np.float64)
            tensors[key + "mode"] = np.array(mode, dtype=np.float64)
            tensors[key + "points"] = np.array(pts, dtype=np.int64)
            tensors[key + "window_points"] = np.array(win, dtype=np.int64)
            tensors[key + "gap"] = np.array(gap, dtype=np.float64)
        raw = [v for v in per["default"][0] if not math.isnan(v)]
        aligned, compat = kalman(raw)
        tensors[scene + "/kalman"] = aligned
        tensors[scene + "/kalman_compat"] = compat
    safetensors_io.save(os.path.join(args.out, "shle_stage2.safetensors"), tensors,
                        {"scenes": ",".join(scenes), "configs": ",".join(n for n, _ in CONFIGS)})
    print("wrote %d tensors for %d scenes" % (len(tensors), len(scenes)))


if __name__ == "__main__":
    main()
