"""Reference for the MIL tracker: OpenCV's own cv2.TrackerMIL (Debian's
python3-opencv, OpenCV 4.6) on rendered sequences, as the released SHLE code
calls it (BGR frames, default parameters, init with an int (x, y, w, h) box).

Renders textured objects moving with sub-pixel steps over panning textured
backgrounds (bilinear, in numpy), runs one cv2.TrackerMIL per sequence in this
one process, in the order listed (OpenCV's Haar features use the process's
rand(), so later trackers continue its sequence, as the released script's gaps
do), and writes OUT/shle_mil.safetensors:
  <name>.frames   U8  [N, H, W]  channel 0 (blue) of the BGR frames, what MIL reads
  <name>.boxes    I32 [N, 4]     x, y, w, h: the init box, then every update's box
  <name>.ok       U8  [N]        1 when init / update returned True
  integral        F32 [H+1, W+1] channel 0 of cv2.integral(first frame of `drive`, CV_32F)
  <level>.integral, <level>.boxes: the same integral and a fresh tracker's boxes on
                  `drive`, from a child process in which OPENCV_CPU_DISABLE makes OpenCV
                  dispatch a lower SIMD level (AVX2, then SSE4), whose float integral
                  rounds differently
metadata: sequences (comma-separated, in run order), opencv (cv2.__version__),
integral_of (the sequence whose first frame is in `integral`), lanes (the SIMD block
width of OpenCV's integral in this process: 32 AVX-512, 16 AVX2, 8 otherwise),
levels (level:lanes,... of the child processes).

With --synth SCENE (a sequence shle_synth wrote in the released layout) it instead
fills gaps as the released stage 1 does: every GAP-th frame is a seed (its LabelMe
box truncated to int x, y, w, h, a new cv2.TrackerMIL), the frames between are
tracked; writes OUT/shle_mil_synth.safetensors with frames (U8 [N, H, W], channel
0 of cv2.imread), seeds (I32 [S]: frame indices), boxes (I32 [N, 4]) and ok (U8 [N]).
"""
import argparse
import os
import subprocess
import sys
import tempfile

INSTALL_HINT = ("the MIL tracker reference needs OpenCV's Python module for /usr/bin/python3: "
                "apt-get install -y python3-opencv python3-numpy")

try:
    import numpy as np
    import cv2
except ImportError as e:
    sys.exit("error: %s (%s)" % (INSTALL_HINT, e))

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "weights"))
import safetensors_io  # noqa: E402


def smooth_texture(rng, h, w, scale):
    """Colour texture: white noise blurred at `scale` px plus fine noise, 0..255 float, BGR."""
    out = np.empty((h, w, 3), np.float64)
    for c in range(3):
        coarse = rng.random((h // scale + 2, w // scale + 2))
        ys = np.linspace(0, coarse.shape[0] - 1.001, h)
        xs = np.linspace(0, coarse.shape[1] - 1.001, w)
        y0, x0 = ys.astype(int), xs.astype(int)
        fy, fx = (ys - y0)[:, None], (xs - x0)[None, :]
        a = coarse[y0][:, x0] * (1 - fx) + coarse[y0][:, x0 + 1] * fx
        b = coarse[y0 + 1][:, x0] * (1 - fx) + coarse[y0 + 1][:, x0 + 1] * fx
        out[:, :, c] = 200 * (a * (1 - fy) + b * fy) + 55 * rng.random((h, w))
    return out


def sample_bilinear(tex, ys, xs):
    """tex sampled at float coordinates (clamped), bilinear."""
    h, w = tex.shape[:2]
    ys = np.clip(ys, 0, h - 1.0001)
    xs = np.clip(xs, 0, w - 1.0001)
    y0, x0 = ys.astype(int), xs.astype(int)
    fy, fx = (ys - y0)[..., None], (xs - x0)[..., None]
    return ((tex[y0, x0] * (1 - fx) + tex[y0, x0 + 1] * fx) * (1 - fy)
            + (tex[y0 + 1, x0] * (1 - fx) + tex[y0 + 1, x0 + 1] * fx) * fy)


def render(spec):
    """Frames (uint8 BGR) of one sequence and the integer init box."""
    rng = np.random.default_rng(spec["seed"])
    h, w, n = spec["height"], spec["width"], spec["frames"]
    bg = smooth_texture(rng, h + 200, w + 200, spec["bg_scale"])
    ow, oh = spec["object"]
    obj = smooth_texture(rng, oh, ow, 6) * 0.6 + 90
    frames = []
    gy, gx = np.mgrid[0:h, 0:w].astype(np.float64)
    for t in range(n):
        pan = np.array(spec["pan"]) * t
        img = sample_bilinear(bg, gy + 100 + pan[1], gx + 100 + pan[0])
        px = spec["start"][0] + spec["velocity"][0] * t + spec["wobble"] * np.sin(0.7 * t)
        py = spec["start"][1] + spec["velocity"][1] * t + spec["wobble"] * np.cos(0.5 * t)
        y0, y1 = max(0, int(np.floor(py))), min(h, int(np.ceil(py + oh)))
        x0, x1 = max(0, int(np.floor(px))), min(w, int(np.ceil(px + ow)))
        ly, lx = gy[y0:y1, x0:x1] - py, gx[y0:y1, x0:x1] - px
        inside = (ly >= 0) & (ly <= oh - 1) & (lx >= 0) & (lx <= ow - 1)
        patch = sample_bilinear(obj, ly, lx)
        region = img[y0:y1, x0:x1]
        region[inside] = patch[inside]
        frames.append(np.clip(np.rint(img), 0, 255).astype(np.uint8))
    box = (int(spec["start"][0]), int(spec["start"][1]), ow, oh)
    return frames, box


# Run order matters (see above); the C++ test runs one MilTracker through them in this order.
SEQUENCES = [
    dict(name="patch", seed=31, height=240, width=320, frames=30, bg_scale=9, object=(48, 36),
         start=(120.0, 90.0), velocity=(1.37, -0.61), pan=(0.3, 0.1), wobble=1.5),
    # 720 x 1250: sums beyond 2^24 (float rounding of the integral) and a row tail
    # after the last SIMD block (1250 = 39 * 32 + 2).
    dict(name="drive", seed=32, height=720, width=1250, frames=16, bg_scale=14, object=(150, 70),
         start=(560.0, 250.0), velocity=(-3.3, 1.9), pan=(1.1, 0.4), wobble=2.0),
    # Odd size, an object near the top-left corner drifting into it: clipped samples.
    dict(name="corner", seed=33, height=181, width=263, frames=24, bg_scale=5, object=(31, 27),
         start=(14.0, 11.0), velocity=(-0.45, -0.35), pan=(-0.2, 0.25), wobble=0.8),
    # A second gap on the same scene as `patch`: the tracker re-created in the same
    # process (features continue rand()).
    dict(name="patch_again", seed=31, height=240, width=320, frames=12, bg_scale=9, object=(48, 36),
         start=(120.0, 90.0), velocity=(1.37, -0.61), pan=(0.3, 0.1), wobble=1.5),
]


# OpenCV feature names; the composite AVX512-* levels must go too, or the dispatcher keeps them.
NO_AVX512 = "AVX512-SKX,AVX512-CNL,AVX512-CLX,AVX512-ICL,AVX512F,AVX512BW,AVX512CD,AVX512DQ,AVX512VL"
LEVELS = [("avx2", NO_AVX512), ("sse4", NO_AVX512 + ",AVX2")]


def integral_lanes():
    """Block width of cv::integral's SIMD code as OpenCV dispatches it in this process."""
    if cv2.checkHardwareSupport(256):  # CV_CPU_AVX512_SKX
        return 32
    if cv2.checkHardwareSupport(11):  # CV_CPU_AVX2
        return 16
    return 8


def track(frames, box):
    tracker = cv2.TrackerMIL_create()
    tracker.init(frames[0], box)  # 4.6's init returns None; it raises on failure
    boxes, ok = [list(box)], [1]
    for f in frames[1:]:
        good, b = tracker.update(f)
        boxes.append([int(v) for v in b])
        ok.append(1 if good else 0)
    return boxes, ok


def child(path):
    """In a process with lowered dispatch: `drive`'s integral and a fresh tracker's boxes."""
    spec = next(s for s in SEQUENCES if s["name"] == "drive")
    frames, box = render(spec)
    boxes, _ = track(frames, box)
    integral = cv2.integral(frames[0], sdepth=cv2.CV_32F)[:, :, 0].astype(np.float32)
    np.savez(path, integral=integral, boxes=np.array(boxes, np.int32), lanes=integral_lanes())


def labelme_box(path):
    """First shape's points as the int (x, y, w, h) the released code seeds with."""
    import json
    with open(path) as f:
        pts = json.load(f)["shapes"][0]["points"]
    x0, y0 = min(p[0] for p in pts), min(p[1] for p in pts)
    x1, y1 = max(p[0] for p in pts), max(p[1] for p in pts)
    return (int(x0), int(y0), int(x1 - x0), int(y1 - y0))


def synth(scene, out, gap=8):
    import glob
    pngs = sorted(glob.glob(os.path.join(scene, "left_colorimages", "*.png")))
    if not pngs:
        sys.exit("error: no left_colorimages/*.png in %s (run shle_synth first)" % scene)
    frames = []
    for p in pngs:
        img = cv2.imread(p)  # BGR, as the released code reads it
        if img is None:
            sys.exit("error: cv2 cannot read %s" % p)
        frames.append(img)
    boxes, ok, seeds = [], [], []
    for start in range(0, len(frames), gap):
        box = labelme_box(os.path.splitext(pngs[start])[0] + ".json")
        seg_boxes, seg_ok = track(frames[start:start + gap], box)
        seeds.append(start)
        boxes += seg_boxes
        ok += seg_ok
    os.makedirs(out, exist_ok=True)
    path = os.path.join(out, "shle_mil_synth.safetensors")
    safetensors_io.save(path, {
        "frames": np.ascontiguousarray(np.stack([f[:, :, 0] for f in frames])),
        "seeds": np.array(seeds, np.int32),
        "boxes": np.array(boxes, np.int32),
        "ok": np.array(ok, np.uint8)}, {"scene": os.path.basename(os.path.normpath(scene)),
                                         "opencv": cv2.__version__, "lanes": str(integral_lanes())})
    print("%s: %d frames %dx%d, %d seeds, wrote %s" % (scene, len(frames), frames[0].shape[1],
                                                       frames[0].shape[0], len(seeds), path))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", help="output folder")
    ap.add_argument("--synth", metavar="SCENE", help="fill the gaps of this shle_synth sequence instead")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if not hasattr(cv2, "TrackerMIL_create"):
        sys.exit("error: this cv2 (%s) has no TrackerMIL_create; %s" % (cv2.__version__, INSTALL_HINT))
    if args.child:
        child(args.child)
        return
    if not args.out:
        ap.error("--out is required")
    if args.synth:
        synth(args.synth, args.out)
        return
    tensors, names = {}, []
    integral = None
    for spec in SEQUENCES:
        frames, box = render(spec)
        boxes, ok = track(frames, box)
        name = spec["name"]
        names.append(name)
        tensors[name + ".frames"] = np.ascontiguousarray(np.stack([f[:, :, 0] for f in frames]))
        tensors[name + ".boxes"] = np.array(boxes, np.int32)
        tensors[name + ".ok"] = np.array(ok, np.uint8)
        if name == "drive":
            integral = cv2.integral(frames[0], sdepth=cv2.CV_32F)[:, :, 0].astype(np.float32)
        moved = np.abs(np.diff(np.array(boxes)[:, :2], axis=0)).sum(axis=1)
        print("%s: %d frames %dx%d, box %s -> %s, moved on %d updates"
              % (name, len(frames), spec["width"], spec["height"], boxes[0], boxes[-1], int((moved > 0).sum())))
    tensors["integral"] = np.ascontiguousarray(integral)
    levels = []
    with tempfile.TemporaryDirectory() as tmp:
        for level, disable in LEVELS:
            out = os.path.join(tmp, level + ".npz")
            env = dict(os.environ, OPENCV_CPU_DISABLE=disable)
            subprocess.run([sys.executable, os.path.abspath(__file__), "--child", out], env=env, check=True)
            got = np.load(out)
            tensors[level + ".integral"] = np.ascontiguousarray(got["integral"])
            tensors[level + ".boxes"] = got["boxes"]
            levels.append("%s:%d" % (level, int(got["lanes"])))
            print("%s (integral lanes %d): drive box %s -> %s"
                  % (level, int(got["lanes"]), got["boxes"][0].tolist(), got["boxes"][-1].tolist()))
    os.makedirs(args.out, exist_ok=True)
    path = os.path.join(args.out, "shle_mil.safetensors")
    safetensors_io.save(path, tensors, {"sequences": ",".join(names), "opencv": cv2.__version__,
                                        "integral_of": "drive", "lanes": str(integral_lanes()),
                                        "levels": ",".join(levels)})
    print("wrote", path)


if __name__ == "__main__":
    main()
