#!/usr/bin/python3
"""Reference outputs of detectron2's Faster R-CNN R50-FPN (faster_rcnn_R_50_FPN_3x,
NUM_CLASSES from the weights) for the detectron2 detector tests.

detectron2 is no Debian package: this is a plain torch / torchvision / numpy
re-implementation of its inference path written from shared/reference/detectron2.md
(§3: every difference from torchvision), which the reference reports reproduced
detectron2 bit for bit. Also checks the numpy port of Pillow's resize
(pillow_resize_ref.py) against Pillow itself, bitwise.

Writes into --out:
  d2_model_final.pth           a trainer checkpoint {"model", "trainer", "iteration"} with
                               seeded random weights under detectron2's names (K=2)
  d2_model_final_numpy.pkl     the same as a pickle of numpy arrays (model zoo .pkl style)
  d2_weights.safetensors       d2_model_final.pth converted by weights/export.py
  d2_weights_from_pkl.safetensors  the .pkl converted the same way
  d2_<case>.safetensors        'input' U8 [H,W,3] RGB; 'resized' U8 [h,w,3]; 'proposals'
                               [P,4] (resized pixels), 'proposal_logits' [P]; 'boxes' [K,4],
                               'scores' [K], 'classes' I64 [K] (0-based, original pixels);
                               the small case also 'transform_size' [min_size, max_size]
ROADNN_TEST_SIZES=small: only the small case.
"""
import collections
import math
import os
import pickle
import subprocess
import sys
import zlib

import numpy as np

import pillow_resize_ref
import refcommon

# 720p upscales to 750x1333, 1080p downscales (antialiased) to 750x1333, 500x740
# becomes 800x1184, padded 800x1184: P5 25x37 and P6 13x19, both odd.
# small: 180x240 upscaled to 240x320 by MIN_SIZE_TEST 240, MAX_SIZE_TEST 320 (the same
# weights and code on a small image, for the emulated aarch64 run).
CASES = {"720p": (720, 1280), "1080p": (1080, 1920), "odd": (500, 740), "small": (180, 240)}
TRANSFORM_SIZES = {"small": (240, 320)}  # (min_size, max_size) of cases not at 800 / 1333
MEAN_BGR = (103.530, 116.280, 123.675)
BLOCKS = (3, 4, 6, 3)
CLASSES = 2  # foreground classes K


def state_dict_names(k):
    """(name, shape) of the checkpoint's tensors, in its order (detectron2.md §4)."""
    out = []

    def conv_bn(prefix, shape):
        out.append((prefix + ".weight", shape))
        for leaf in ("weight", "bias", "running_mean", "running_var"):
            out.append((prefix + ".norm." + leaf, (shape[0],)))

    conv_bn("backbone.bottom_up.stem.conv1", (64, 3, 7, 7))
    cin = 64
    for s, n in enumerate(BLOCKS):
        w = 64 << s
        for i in range(n):
            b = f"backbone.bottom_up.res{s + 2}.{i}"
            if i == 0:
                conv_bn(b + ".shortcut", (4 * w, cin, 1, 1))
            conv_bn(b + ".conv1", (w, cin, 1, 1))
            conv_bn(b + ".conv2", (w, w, 3, 3))
            conv_bn(b + ".conv3", (4 * w, w, 1, 1))
            cin = 4 * w
    for lvl, c in zip((2, 3, 4, 5), (256, 512, 1024, 2048)):
        out += [(f"backbone.fpn_lateral{lvl}.weight", (256, c, 1, 1)), (f"backbone.fpn_lateral{lvl}.bias", (256,)),
                (f"backbone.fpn_output{lvl}.weight", (256, 256, 3, 3)), (f"backbone.fpn_output{lvl}.bias", (256,))]
    h = "proposal_generator.rpn_head."
    out += [(h + "conv.weight", (256, 256, 3, 3)), (h + "conv.bias", (256,)),
            (h + "objectness_logits.weight", (3, 256, 1, 1)), (h + "objectness_logits.bias", (3,)),
            (h + "anchor_deltas.weight", (12, 256, 1, 1)), (h + "anchor_deltas.bias", (12,))]
    r = "roi_heads."
    out += [(r + "box_head.fc1.weight", (1024, 12544)), (r + "box_head.fc1.bias", (1024,)),
            (r + "box_head.fc2.weight", (1024, 1024)), (r + "box_head.fc2.bias", (1024,)),
            (r + "box_predictor.cls_score.weight", (k + 1, 1024)), (r + "box_predictor.cls_score.bias", (k + 1,)),
            (r + "box_predictor.bbox_pred.weight", (4 * k, 1024)), (r + "box_predictor.bbox_pred.bias", (4 * k,))]
    return out


def random_weights(torch, k, seed):
    """Seeded weights at the project's scales (refcommon.init_weights): conv/linear
    N(0, 1/fan_in), norm gamma N(1, 0.2), beta N(0, 0.1), biases N(0, 0.05); FrozenBN
    running statistics randomised too."""
    g = torch.Generator().manual_seed(seed)
    sd = collections.OrderedDict()
    for name, shape in state_dict_names(k):
        norm = ".norm." in name
        if norm and name.endswith("running_mean"):
            t = 0.1 * torch.randn(shape, generator=g)
        elif norm and name.endswith("running_var"):
            t = torch.rand(shape, generator=g) + 0.5
        elif norm and name.endswith("weight"):
            t = 1.0 + 0.2 * torch.randn(shape, generator=g)
        elif name.endswith("bias"):
            t = (0.1 if norm else 0.05) * torch.randn(shape, generator=g)
        else:
            fan_in = int(np.prod(shape[1:]))
            t = torch.randn(shape, generator=g) / fan_in ** 0.5
        sd[name] = t.float()
    return sd


# ---------------------------------------------------------------- the model, §3.1-3.14

def output_size(h, w, short=800, max_size=1333):
    """ResizeShortestEdge.get_output_shape (double; int(x + 0.5))."""
    scale = short * 1.0 / min(h, w)
    newh, neww = (short, scale * w) if h < w else (scale * h, short)
    if max(newh, neww) > max_size:
        s = max_size * 1.0 / max(newh, neww)
        newh, neww = newh * s, neww * s
    return int(newh + 0.5), int(neww + 0.5)


def pil_resize(rgb, h, w):
    """ResizeTransform.apply_image for uint8: Pillow's bilinear resize."""
    from PIL import Image
    if rgb.shape[:2] == (h, w):
        return rgb.copy()
    return np.asarray(Image.fromarray(rgb).resize((w, h), Image.BILINEAR))


class Detectron2:
    def __init__(self, torch, sd):
        self.t, self.sd = torch, sd
        self.F = torch.nn.functional
        self.sizes = (800, 1333)  # INPUT.MIN_SIZE_TEST, MAX_SIZE_TEST

    def conv_bn(self, x, name, stride=1, pad=0, relu=True):
        F, sd = self.F, self.sd
        x = F.conv2d(x, sd[name + ".weight"], None, stride, pad)
        x = F.batch_norm(x, sd[name + ".norm.running_mean"], sd[name + ".norm.running_var"],
                         sd[name + ".norm.weight"], sd[name + ".norm.bias"], False, 0.0, 1e-5)
        return F.relu_(x) if relu else x

    def bottom_up(self, x):
        F = self.F
        x = self.conv_bn(x, "backbone.bottom_up.stem.conv1", 2, 3)
        x = F.max_pool2d(x, kernel_size=3, stride=2, padding=1)
        outs = []
        for s, n in enumerate(BLOCKS):
            for i in range(n):
                b = f"backbone.bottom_up.res{s + 2}.{i}"
                stride = 2 if (i == 0 and s > 0) else 1
                # STRIDE_IN_1X1: the stride in conv1, conv2 at stride 1
                y = self.conv_bn(x, b + ".conv1", stride, 0)
                y = self.conv_bn(y, b + ".conv2", 1, 1)
                y = self.conv_bn(y, b + ".conv3", 1, 0, relu=False)
                short = self.conv_bn(x, b + ".shortcut", stride, 0, relu=False) if i == 0 else x
                x = F.relu_(y + short)
            outs.append(x)
        return outs

    def fpn(self, feats):
        F, sd = self.F, self.sd
        results = []
        prev = F.conv2d(feats[3], sd["backbone.fpn_lateral5.weight"], sd["backbone.fpn_lateral5.bias"])
        results.append(F.conv2d(prev, sd["backbone.fpn_output5.weight"], sd["backbone.fpn_output5.bias"], 1, 1))
        for lvl in (4, 3, 2):
            top_down = F.interpolate(prev, scale_factor=2.0, mode="nearest")
            lateral = F.conv2d(feats[lvl - 2], sd[f"backbone.fpn_lateral{lvl}.weight"],
                               sd[f"backbone.fpn_lateral{lvl}.bias"])
            prev = lateral + top_down
            results.insert(0, F.conv2d(prev, sd[f"backbone.fpn_output{lvl}.weight"],
                                       sd[f"backbone.fpn_output{lvl}.bias"], 1, 1))
        results.append(F.max_pool2d(results[-1], kernel_size=1, stride=2, padding=0))
        return results  # p2..p6

    def anchors(self, grids):
        torch = self.t
        out = []
        for (gh, gw), size, stride in zip(grids, (32, 64, 128, 256, 512), (4, 8, 16, 32, 64)):
            cell = []
            area = size ** 2.0
            for r in (0.5, 1.0, 2.0):
                w = math.sqrt(area / r)
                h = r * w
                cell.append([-w / 2.0, -h / 2.0, w / 2.0, h / 2.0])
            cell = torch.tensor(cell, dtype=torch.float32)
            sx = torch.arange(0, gw * stride, step=stride, dtype=torch.float32)
            sy = torch.arange(0, gh * stride, step=stride, dtype=torch.float32)
            yy, xx = torch.meshgrid(sy, sx, indexing="ij")
            xx, yy = xx.reshape(-1), yy.reshape(-1)
            shifts = torch.stack((xx, yy, xx, yy), dim=1)
            out.append((shifts.view(-1, 1, 4) + cell.view(1, -1, 4)).reshape(-1, 4))
        return out

    @staticmethod
    def apply_deltas(torch, deltas, boxes, weights):
        clip = math.log(1000.0 / 16)
        widths = boxes[:, 2] - boxes[:, 0]
        heights = boxes[:, 3] - boxes[:, 1]
        ctr_x = boxes[:, 0] + 0.5 * widths
        ctr_y = boxes[:, 1] + 0.5 * heights
        wx, wy, ww, wh = weights
        dx = deltas[:, 0::4] / wx
        dy = deltas[:, 1::4] / wy
        dw = torch.clamp(deltas[:, 2::4] / ww, max=clip)
        dh = torch.clamp(deltas[:, 3::4] / wh, max=clip)
        pcx = dx * widths[:, None] + ctr_x[:, None]
        pcy = dy * heights[:, None] + ctr_y[:, None]
        pw = torch.exp(dw) * widths[:, None]
        ph = torch.exp(dh) * heights[:, None]
        x1, y1 = pcx - 0.5 * pw, pcy - 0.5 * ph
        x2, y2 = pcx + 0.5 * pw, pcy + 0.5 * ph
        return torch.stack((x1, y1, x2, y2), dim=-1).view(deltas.shape)

    @staticmethod
    def clip(boxes, h, w):
        x1 = boxes[:, 0].clamp(min=0, max=w)
        y1 = boxes[:, 1].clamp(min=0, max=h)
        x2 = boxes[:, 2].clamp(min=0, max=w)
        y2 = boxes[:, 3].clamp(min=0, max=h)
        import torch
        return torch.stack((x1, y1, x2, y2), dim=-1)

    def rpn(self, pyramid, image_size):
        torch, F, sd = self.t, self.F, self.sd
        from torchvision.ops import batched_nms
        h = "proposal_generator.rpn_head."
        anchors = self.anchors([p.shape[-2:] for p in pyramid])
        boxes_all, logits_all, lvl_all = [], [], []
        for lvl, (p, anc) in enumerate(zip(pyramid, anchors)):
            t = F.relu(F.conv2d(p, sd[h + "conv.weight"], sd[h + "conv.bias"], 1, 1))
            logits = F.conv2d(t, sd[h + "objectness_logits.weight"], sd[h + "objectness_logits.bias"])
            deltas = F.conv2d(t, sd[h + "anchor_deltas.weight"], sd[h + "anchor_deltas.bias"])
            logits = logits.permute(0, 2, 3, 1).flatten(1)[0]  # (y, x, a)
            n, _, gh, gw = deltas.shape
            deltas = deltas.view(n, 3, 4, gh, gw).permute(0, 3, 4, 1, 2).reshape(-1, 4)
            proposals = self.apply_deltas(torch, deltas, anc, (1.0, 1.0, 1.0, 1.0))
            k = min(1000, logits.shape[0])
            top, idx = logits.topk(k)
            boxes_all.append(proposals[idx])
            logits_all.append(top)
            lvl_all.append(torch.full((k,), lvl, dtype=torch.int64))
        boxes, logits, lvl = torch.cat(boxes_all), torch.cat(logits_all), torch.cat(lvl_all)
        keep = torch.isfinite(boxes).all(dim=1) & torch.isfinite(logits)
        boxes, logits, lvl = boxes[keep], logits[keep], lvl[keep]
        boxes = self.clip(boxes, *image_size)
        keep = ((boxes[:, 2] - boxes[:, 0]) > 0) & ((boxes[:, 3] - boxes[:, 1]) > 0)
        boxes, logits, lvl = boxes[keep], logits[keep], lvl[keep]
        keep = batched_nms(boxes, logits, lvl, 0.7)[:1000]
        return boxes[keep], logits[keep]

    def roi_heads(self, pyramid, proposals, image_size):
        torch, F, sd = self.t, self.F, self.sd
        from torchvision.ops import batched_nms, roi_align
        area = (proposals[:, 2] - proposals[:, 0]) * (proposals[:, 3] - proposals[:, 1])
        level = torch.floor(4 + torch.log2(torch.sqrt(area) / 224 + 1e-8))
        level = torch.clamp(level, min=2, max=5).to(torch.int64) - 2
        pooled = torch.zeros((proposals.shape[0], 256, 7, 7))
        for lvl in range(4):
            idx = torch.nonzero(level == lvl).squeeze(1)
            rois = torch.cat([torch.zeros((idx.numel(), 1)), proposals[idx]], dim=1)
            pooled[idx] = roi_align(pyramid[lvl], rois, (7, 7), spatial_scale=1.0 / (4 << lvl), sampling_ratio=0,
                                    aligned=True)
        r = "roi_heads."
        x = F.relu(F.linear(pooled.flatten(1), sd[r + "box_head.fc1.weight"], sd[r + "box_head.fc1.bias"]))
        x = F.relu(F.linear(x, sd[r + "box_head.fc2.weight"], sd[r + "box_head.fc2.bias"]))
        scores = F.linear(x, sd[r + "box_predictor.cls_score.weight"], sd[r + "box_predictor.cls_score.bias"])
        deltas = F.linear(x, sd[r + "box_predictor.bbox_pred.weight"], sd[r + "box_predictor.bbox_pred.bias"])
        boxes = self.apply_deltas(torch, deltas, proposals, (10.0, 10.0, 5.0, 5.0))
        probs = F.softmax(scores, dim=-1)
        valid = torch.isfinite(boxes).all(dim=1) & torch.isfinite(probs).all(dim=1)
        boxes, probs = boxes[valid], probs[valid]
        probs = probs[:, :-1]  # the background is the last column
        k = probs.shape[1]
        boxes = self.clip(boxes.reshape(-1, 4), *image_size).view(-1, k, 4)
        mask = probs > 0.05
        inds = mask.nonzero()
        boxes, probs = boxes[mask], probs[mask]
        keep = batched_nms(boxes, probs, inds[:, 1], 0.5)[:100]
        return boxes[keep], probs[keep], inds[keep, 1]

    def preprocess(self, rgb):
        """GeneralizedRCNN.preprocess_image after the mapper: the Pillow resize, BGR,
        normalisation, zero padding to a multiple of 32."""
        torch, F = self.t, self.F
        h, w = output_size(*rgb.shape[:2], *self.sizes)
        resized = pil_resize(rgb, h, w)
        x = torch.as_tensor(np.ascontiguousarray(resized[:, :, ::-1]).astype(np.float32)).permute(2, 0, 1)
        x = (x - torch.tensor(MEAN_BGR).view(3, 1, 1)) / torch.tensor([1.0, 1.0, 1.0]).view(3, 1, 1)
        ph, pw = (h + 31) // 32 * 32, (w + 31) // 32 * 32
        return F.pad(x, (0, pw - w, 0, ph - h), value=0.0)[None], resized

    @staticmethod
    def postprocess(boxes, scores, classes, original, resized):
        """detector_postprocess: scale (Python doubles on float32), clip, nonempty."""
        (H, W), (h, w) = original, resized
        sx, sy = W / w, H / h
        boxes = boxes.clone()
        boxes[:, 0::2] *= sx
        boxes[:, 1::2] *= sy
        boxes = Detectron2.clip(boxes, H, W)
        keep = ((boxes[:, 2] - boxes[:, 0]) > 0) & ((boxes[:, 3] - boxes[:, 1]) > 0)
        return boxes[keep], scores[keep], classes[keep]

    def __call__(self, rgb):
        x, resized = self.preprocess(rgb)
        size = resized.shape[:2]
        pyramid = self.fpn(self.bottom_up(x))
        proposals, logits = self.rpn(pyramid, size)
        boxes, scores, classes = self.postprocess(*self.roi_heads(pyramid[:4], proposals, size), rgb.shape[:2], size)
        return dict(resized=resized, proposals=proposals, proposal_logits=logits, boxes=boxes, scores=scores,
                    classes=classes)


def calibrate(torch, sd, model, rgb):
    """As detector_ref.py: random weights leave the head outputs tiny or saturated;
    rescale the four output layers to logit std 2 and delta std 0.3 on this input so
    proposals and detections are real, distinct decisions."""
    F = torch.nn.functional
    h, w = output_size(*rgb.shape[:2])
    x = torch.as_tensor(np.ascontiguousarray(pil_resize(rgb, h, w)[:, :, ::-1]).astype(np.float32)).permute(2, 0, 1)
    x = x - torch.tensor(MEAN_BGR).view(3, 1, 1)
    x = F.pad(x, (0, (w + 31) // 32 * 32 - w, 0, (h + 31) // 32 * 32 - h))[None]
    pyramid = model.fpn(model.bottom_up(x))
    hd = "proposal_generator.rpn_head."
    ts = [F.relu(F.conv2d(p, sd[hd + "conv.weight"], sd[hd + "conv.bias"], 1, 1)) for p in pyramid]
    for name, target in (("objectness_logits", 2.0), ("anchor_deltas", 0.3)):
        out = torch.cat([F.conv2d(t, sd[hd + name + ".weight"], sd[hd + name + ".bias"]).flatten() for t in ts])
        k = target / float(out.std())
        sd[hd + name + ".weight"] *= k
        sd[hd + name + ".bias"] *= k
    proposals, _ = model.rpn(pyramid, (h, w))
    # the box head's input on these proposals, then its two output layers
    from torchvision.ops import roi_align
    r = "roi_heads."
    rois = torch.cat([torch.zeros((proposals.shape[0], 1)), proposals], dim=1)
    pooled = roi_align(pyramid[1], rois, (7, 7), spatial_scale=1.0 / 8, sampling_ratio=0, aligned=True)
    x = F.relu(F.linear(pooled.flatten(1), sd[r + "box_head.fc1.weight"], sd[r + "box_head.fc1.bias"]))
    x = F.relu(F.linear(x, sd[r + "box_head.fc2.weight"], sd[r + "box_head.fc2.bias"]))
    for name, target in (("cls_score", 2.0), ("bbox_pred", 0.3)):
        out = F.linear(x, sd[r + "box_predictor." + name + ".weight"], sd[r + "box_predictor." + name + ".bias"])
        k = target / float(out.std())
        sd[r + "box_predictor." + name + ".weight"] *= k
        sd[r + "box_predictor." + name + ".bias"] *= k


def make_input(torch, case, h, w):
    """A smooth image plus fine noise (as detector_ref.py), as RGB8."""
    g = torch.Generator().manual_seed(zlib.crc32(("d2" + case).encode()))
    coarse = torch.rand((1, 3, h // 16 + 1, w // 16 + 1), generator=g)
    x = torch.nn.functional.interpolate(coarse, size=(h, w), mode="bilinear", align_corners=False)
    x = (0.8 * x + 0.2 * torch.rand((1, 3, h, w), generator=g)).clamp(0, 1)
    return (x[0].permute(1, 2, 0).numpy() * 255.0 + 0.5).astype(np.uint8)


def check_pillow_port(torch):
    """The numpy port against Pillow, bitwise: up, down (antialiased), one axis only."""
    rng = np.random.default_rng(7)
    for (h, w), (oh, ow) in (((72, 128), (75, 133)), ((108, 192), (75, 133)), ((50, 74), (80, 118)),
                             ((61, 97), (61, 40)), ((33, 45), (90, 45)), ((720, 1280), (750, 1333))):
        img = rng.integers(0, 256, (h, w, 3), dtype=np.uint8)
        ours, pil = pillow_resize_ref.resize(img, oh, ow), pil_resize(img, oh, ow)
        if not np.array_equal(ours, pil):
            sys.exit(f"error: numpy Pillow port differs from Pillow at {h}x{w} -> {oh}x{ow}: "
                     f"{int((ours != pil).sum())} bytes")
    print("numpy port of Pillow's bilinear resize: bitwise equal to Pillow on 6 size pairs")


def main():
    out, _ = refcommon.out_dir(sys.argv[1:])
    torch = refcommon.import_torch()
    check_pillow_port(torch)
    sd = random_weights(torch, CLASSES, seed=2024)
    model = Detectron2(torch, sd)
    with torch.no_grad():
        calibrate(torch, sd, model, make_input(torch, "720p", *CASES["720p"]))
    # The trainer's checkpoint (fvcore Checkpointer.save) and a model-zoo style pickle.
    pth = f"{out}/d2_model_final.pth"
    torch.save({"model": sd, "trainer": {"iteration": 89999, "hooks": {"LRScheduler": {"base_lrs": [0.02],
                "last_epoch": 90000}}}, "iteration": 89999}, pth + ".tmp")
    os.replace(pth + ".tmp", pth)
    with open(f"{out}/d2_model_final_numpy.pkl.tmp", "wb") as f:
        pickle.dump({"model": {k: v.numpy() for k, v in sd.items()}, "__author__": "roadnn test",
                     "matching_heuristics": True}, f)
    os.replace(f"{out}/d2_model_final_numpy.pkl.tmp", f"{out}/d2_model_final_numpy.pkl")
    export = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "weights", "export.py")
    subprocess.run([sys.executable, export, pth, f"{out}/d2_weights.safetensors"], check=True)
    subprocess.run([sys.executable, export, f"{out}/d2_model_final_numpy.pkl", f"{out}/d2_weights_from_pkl.safetensors"],
                   check=True)
    for case, (h, w) in CASES.items():
        if refcommon.small_sizes() and case not in TRANSFORM_SIZES:
            continue
        rgb = make_input(torch, case, h, w)
        model.sizes = TRANSFORM_SIZES.get(case, (800, 1333))
        with torch.no_grad():
            r = model(rgb)
        oh, ow = output_size(h, w, *model.sizes)
        assert np.array_equal(pillow_resize_ref.resize(rgb, oh, ow), r["resized"]), case
        s = r["scores"]
        print(f"d2/{case}: resized {r['resized'].shape[:2]}, {r['proposals'].shape[0]} proposals, "
              f"{s.shape[0]} detections, scores {float(s.min()) if len(s) else 0:.3f}.."
              f"{float(s.max()) if len(s) else 0:.3f}")
        tensors = {"input": rgb, "resized": r["resized"], "proposals": r["proposals"],
                   "proposal_logits": r["proposal_logits"], "boxes": r["boxes"], "scores": r["scores"],
                   "classes": r["classes"]}
        if case in TRANSFORM_SIZES:
            tensors["transform_size"] = np.array(TRANSFORM_SIZES[case], dtype=np.int64)
        refcommon.save(f"{out}/d2_{case}.safetensors", tensors)


if __name__ == "__main__":
    main()
