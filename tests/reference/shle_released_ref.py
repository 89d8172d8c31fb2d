"""Reference for `shle` fed with the released SHLE stage-1 artefacts, following the
released code (github.com/Yang-Kaixing/SHLE, commit 4a941c3) as described in
../shared/reference/shle.md sections 1-5:

Stage 1 (Stage1/tracking_faster_rcnn.py), from a detectron2-style results file:
  keep records with score > 0.3; per image_id keep the box with the largest
  bbox[2] (the width; first maximum wins); the image is image_list[image_id - 1]
  of the COCO dataset file; write <name up to the first '.'>.json holding one
  LabelMe-shaped shape with points [[x, y], [w, h]]. The released code then fills
  the frames strictly between two detections with cv2.TrackerMIL; here a stand-in
  "tracker" writes the annotation box moved by a seeded +-3 px jitter with the
  seeding detection's size truncated to int (MIL keeps the size and moves by whole
  pixels): any box serves, stage 2 only reads the files.

Stage 2 (Stage2/post_process.py): the stage-1 files in sorted order; the frame
  gate compute_pred_success against the first shape of the frame's LabelMe
  annotation (IoU on int-truncated corners with +1, or |A.x1 - B.x0| < 200 and
  |A.y0 - B.y0| < 20); stage 2 of the kept frames (shle_stage2_ref.stage2, released
  defaults); NaN heights dropped; the released Kalman (Q = 1e-3, R = 1e-2, P0 = 6,
  x0 = z0) with its off-by-one output x1..x(n-1), 0.0.

Inputs: the synthetic sequences in released layout that the shle_synth_* fixtures
write to OUT/shle_synth/ (their detections.csv is the simulated detector). Per
scene this writes OUT/shle_released/<scene>/:
  coco_instances_results.json  image ids in a shuffled listing order (as sahi's
                               os.walk listing), plus two distractors per scene
                               that the widest rule picks and the gate has to judge;
  test2017_images.json         that listing ({"images": [{"id", "file_name"}]});
  coco_sorted_results.json     the same records with ids in file-name order;
  stage1/                      the released stage-1 files (detections + stand-in
                               tracker boxes);
and OUT/shle_released.safetensors with, per scene and variant ("stage1": the
stage-1 folder; "coco": the detections alone, i.e. what shle computes from the
results file with --tracker none), per frame in file-name order: raw and
filtered heights (NaN = none), the gate flag and the KDE gap.
"""
import json
import math
import os
import random
import sys

try:
    import numpy as np
except ImportError as e:  # pragma: no cover
    sys.exit("error: the SHLE reference needs numpy for /usr/bin/python3: apt-get install -y python3-numpy (%s)" % e)

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "..", "weights"))
import safetensors_io  # noqa: E402
import shle_stage2_ref as s2  # noqa: E402

SCORE_MIN = 0.3


def f32(v):
    """detectron2's boxes are float32 tensors turned into Python floats."""
    return float(np.float32(v))


def released_iou(a, b):
    a = [int(v) for v in a]
    b = [int(v) for v in b]
    xa, ya = max(a[0], b[0]), max(a[1], b[1])
    xb, yb = min(a[2], b[2]), min(a[3], b[3])
    inter = max(0, xb - xa + 1) * max(0, yb - ya + 1)
    area_a = (a[2] - a[0] + 1) * (a[3] - a[1] + 1)
    area_b = (b[2] - b[0] + 1) * (b[3] - b[1] + 1)
    return inter / float(area_a + area_b - inter)


def released_gate(pred_file, gt_file):
    """compute_pred_success: (box as corners, flag)."""
    with open(pred_file) as f:
        p = json.load(f)["shapes"][0]["points"]
    box_a = [p[0][0], p[0][1], p[0][0] + p[1][0], p[0][1] + p[1][1]]
    with open(gt_file) as f:
        g = json.load(f)["shapes"][0]["points"]
    box_b = [g[0][0], g[0][1], g[1][0], g[1][1]]
    row_dis = abs(box_a[2] - box_b[0])
    col_dis = abs(box_a[1] - box_b[1])
    flag = released_iou(box_a, box_b) > 0.0 or (row_dis < 200 and col_dis < 20)
    return box_a, flag


def save_stage1(path, name, bbox):
    """The released save_json: points [[x, y], [w, h]], fixed 1280 x 720."""
    doc = {"version": "4.5.9", "flags": {},
           "shapes": [{"label": "height", "points": [[float(bbox[0]), float(bbox[1])], [float(bbox[2]), float(bbox[3])]],
                       "shape_type": "rectangle", "flags": {}}],
           "imagePath": name + ".png", "imageHeight": 720, "imageWidth": 1280}
    with open(os.path.join(path, name + ".json"), "w") as f:
        f.write(json.dumps(doc, indent=2))


def read_detections(path):
    out = []
    with open(path) as f:
        next(f)
        for line in f:
            fr, x0, y0, x1, y1, sc = line.strip().split(",")
            out.append((int(fr), float(x0), float(y0), float(x1), float(y1), float(sc)))
    return out


def gt_box(lm_path):
    with open(lm_path) as f:
        p = json.load(f)["shapes"][0]["points"]
    return [p[0][0], p[0][1], p[1][0], p[1][1]]


def write_inputs(scene_dir, out_dir, seed):
    """Writes the COCO files and the stage-1 folder; returns the stage-1 folder and
    the set of frame stems that have a detection."""
    frames = s2.sequence_frames(scene_dir)
    names = [stem + ".png" for stem, _, _, _ in frames]
    rng = random.Random(seed)
    listing = list(range(len(names)))
    rng.shuffle(listing)  # sahi lists os.walk order, not sorted
    id_of = {frame: k + 1 for k, frame in enumerate(listing)}
    img_dir = os.path.join(os.path.abspath(scene_dir), "left_colorimages")
    images = [{"id": k + 1, "file_name": os.path.join(img_dir, names[frame]), "height": 720, "width": 1280}
              for k, frame in enumerate(listing)]
    with open(os.path.join(out_dir, "test2017_images.json"), "w") as f:
        json.dump({"images": images, "annotations": [], "categories": [{"id": 1, "name": "height"}]}, f)

    records = []  # (frame, x, y, w, h, score)
    for fr, x0, y0, x1, y1, sc in read_detections(os.path.join(scene_dir, "detections.csv")):
        records.append((fr, f32(x0), f32(y0), f32(x1 - x0), f32(y1 - y0), sc))
    # Distractors for the gate: frame 1 a wide box across the buildings above the
    # device (widest; it has a height, far too high, and fails the gate); frame 2 a box left of the device ending within 200 px of its left
    # edge, top within 20 px (passes the gate by distance, not by IoU), plus a
    # wider box with score exactly 0.3 (not > 0.3: must be ignored).
    g1 = gt_box(frames[1][1])
    records.append((1, f32(20.0), f32(30.0), f32(1200.0), f32(60.0), 0.61))
    g2 = gt_box(frames[2][1])
    x_left = max(0.0, g2[0] - 420.0)
    if g2[0] - 60.0 - x_left >= 10.0:  # room left of the device
        records.append((2, f32(x_left), f32(g2[1] + 5.0), f32(g2[0] - 60.0 - x_left), f32(40.0), 0.55))
    records.append((2, f32(0.0), f32(650.0), f32(1279.0), f32(60.0), 0.3))
    del g1
    coco = [{"image_id": id_of[fr], "category_id": 1, "bbox": [x, y, w, h], "score": sc}
            for fr, x, y, w, h, sc in records]
    with open(os.path.join(out_dir, "coco_instances_results.json"), "w") as f:
        json.dump(coco, f)
    coco_sorted = [dict(r, image_id=fr + 1) for r, (fr, *_rest) in zip(coco, records)]
    with open(os.path.join(out_dir, "coco_sorted_results.json"), "w") as f:
        json.dump(coco_sorted, f)

    # Released stage 1: score > 0.3, widest per image (first maximum), file by name.
    image_list = [{"id": im["id"], "file_name": im["file_name"]} for im in images]
    handler = {}
    for r in coco:
        if r["score"] > SCORE_MIN:
            handler.setdefault(r["image_id"], []).append(r["bbox"])
    chosen = []
    for image_id, boxes in handler.items():
        widths = [float(b[2]) for b in boxes]
        box = boxes[widths.index(max(widths))]
        name = image_list[image_id - 1]["file_name"].split("/")[-1].split(".")[0]
        chosen.append((name, box))
    chosen.sort()
    stage1 = os.path.join(out_dir, "stage1")
    stage1_det = os.path.join(out_dir, "stage1_detections")
    for d in (stage1, stage1_det):
        os.makedirs(d, exist_ok=True)
        for n in os.listdir(d):
            os.remove(os.path.join(d, n))
    for name, box in chosen:
        save_stage1(stage1, name, box)
        save_stage1(stage1_det, name, box)
    # Stand-in tracker between consecutive detections (file-name order).
    stems = [stem for stem, _, _, _ in frames]
    lm_of = {stem: lm for stem, lm, _, _ in frames}
    pos = {stem: k for k, stem in enumerate(stems)}
    for (n1, b1), (n2, _) in zip(chosen, chosen[1:]):
        w, h = int(b1[2]), int(b1[3])
        for k in range(pos[n1] + 1, pos[n2]):
            g = gt_box(lm_of[stems[k]])
            x = min(max(int(g[0]) + rng.randint(-3, 3), 0), 1280 - w)
            y = min(max(int(g[1]) + rng.randint(-3, 3), 0), 720 - h)
            save_stage1(stage1, stems[k], [float(x), float(y), float(w), float(h)])
    return stage1, stage1_det


def kalman_released(z, q=1e-3, r=1e-2, p0=6.0):
    """The released kalman(): arrays of n + 1, entries 1..n returned."""
    n_iter = len(z) + 1
    xhat = np.zeros(n_iter)
    P = np.zeros(n_iter)
    xhat[0] = z[0]
    P[0] = p0
    for k in range(1, n_iter - 1):
        p_minus = P[k - 1] + q
        K = p_minus / (p_minus + r)
        xhat[k] = xhat[k - 1] + K * (z[k] - xhat[k - 1])
        P[k] = (1 - K) * p_minus
    return xhat[1:]


def released_stage2(scene_dir, stage1_dir, cal, frames):
    """Per frame (file-name order): raw height, filtered height, gate flag (-1 = no
    stage-1 file), KDE gap."""
    n = len(frames)
    raw = [math.nan] * n
    flags = [-1] * n
    gaps = [math.inf] * n
    index = {stem: k for k, (stem, _, _, _) in enumerate(frames)}
    used = []
    for name in sorted(os.listdir(stage1_dir)):
        stem = name.split(".")[0]
        k = index[stem]
        _, lm, dpath, _ = frames[k]
        box, flag = released_gate(os.path.join(stage1_dir, name), lm)
        flags[k] = int(flag)
        if not flag:
            continue
        disp = s2.read_dat(dpath, cal["width"], cal["height"])
        h, _mode, _pts, _win, gap = s2.stage2(disp, list(box), cal)
        gaps[k] = gap
        if not math.isnan(h):
            raw[k] = h
            used.append(k)
    filtered = [math.nan] * n
    if used:
        for k, v in zip(used, kalman_released([raw[k] for k in used])):
            filtered[k] = float(v)
    return raw, filtered, flags, gaps


def main():
    import argparse
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    root = os.path.join(args.out, "shle_synth")
    scenes = sorted(n for n in os.listdir(root)
                    if os.path.isdir(os.path.join(root, n, "left_colorimages")))
    if not scenes:
        sys.exit("error: no synthetic scenes in released layout in %s (the shle_synth fixtures write them)" % root)
    tensors = {}
    gated = 0
    for seed, scene in enumerate(scenes, start=1):
        sdir = os.path.join(root, scene)
        out_dir = os.path.join(args.out, "shle_released", scene)
        os.makedirs(out_dir, exist_ok=True)
        cal = s2.read_calib(os.path.join(sdir, "calib.json"))
        frames = s2.sequence_frames(sdir)
        stage1, stage1_det = write_inputs(sdir, out_dir, seed)
        for variant, d in (("stage1", stage1), ("coco", stage1_det)):
            raw, filtered, flags, gaps = released_stage2(sdir, d, cal, frames)
            key = "%s/%s/" % (scene, variant)
            tensors[key + "raw"] = np.array(raw, dtype=np.float64)
            tensors[key + "filtered"] = np.array(filtered, dtype=np.float64)
            tensors[key + "gate"] = np.array(flags, dtype=np.int64)
            tensors[key + "gap"] = np.array(gaps, dtype=np.float64)
            gated += sum(1 for f in flags if f == 0)
    safetensors_io.save(os.path.join(args.out, "shle_released.safetensors"), tensors,
                        {"scenes": ",".join(scenes), "gated_out": str(gated)})
    print("wrote %d tensors for %d scenes (%d frames gated out)" % (len(tensors), len(scenes), gated))


if __name__ == "__main__":
    main()
