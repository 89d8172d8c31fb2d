#!/usr/bin/python3
"""PyTorch reference of StixelNExT++ (torchvision ConvNeXt-Tiny features -> mean over
feature rows -> stixel head) for every head variant (modules: weights/torch_models.py). Writes into --out:
  stixel_<variant>_weights.safetensors   features.* + classifier.* state_dict
  stixel_case_<variant>_<size>.safetensors   'input' [1,3,H,W], 'expected' [1,A,64,U]
                                             (v4 also 'authors_d' [64,U]: see authors_depths)
Variants: v4 (latest), v1 (local column attention), v3 (global), v2 (attention unused),
v0 (plain reduce). Sizes: fullhd (1280x1920, U = 240) and small (256x640, U = 80); with
ROADNN_TEST_SIZES=small only small, at 64x160, U = 20."""
import sys

import refcommon
import torch_models  # weights/, on the path through refcommon

SIZES = {"small": (256, 640, 80), "fullhd": (1280, 1920, 240)}
if refcommon.small_sizes():  # under emulation (test_stixelnext_torch.cpp's small_size())
    SIZES = {"small": (64, 160, 20)}
VARIANTS = ("v4", "v1", "v3", "v2", "v0")


def authors_depths(np, prediction):
    """StixelNExT_Pro's revert_class depth of every candidate of a recorded V4
    prediction [A, 64, U]: its tangent create_depth_bins (4, 66, 64) table in
    float64, then _decode_depth_residual, float(exp(log(max(anchor, 1e-6)) +
    float(d_res))) on numpy float64 scalars, stored as float32 by protobuf."""
    lin = np.linspace(0, np.pi / 2.72, 64)
    t = np.tan(lin)
    anchors = 4 + (t - t.min()) / (t.max() - t.min()) * (66 - 4)
    pred = prediction.numpy()
    d = np.empty(pred.shape[1:], dtype=np.float32)
    for n in range(pred.shape[1]):
        anchor = max(float(anchors[n]), 1e-6)
        for u in range(pred.shape[2]):
            d[n, u] = np.float32(float(np.exp(np.log(anchor) + float(pred[2, n, u]))))
    return d


def main():
    out, only = refcommon.out_dir(sys.argv[1:])
    torch = refcommon.import_torch()
    backbone = torch_models.convnext(torch, "convnext_tiny")
    refcommon.init_weights(backbone, seed=1234)
    backbone.eval()
    feats = {}
    for size, (h, w, _) in SIZES.items():
        if only and not any(o.endswith(size) for o in only):
            continue
        x = torch.rand((1, 3, h, w), generator=torch.Generator().manual_seed(h + w)) * 255.0
        with torch.no_grad():
            f = backbone.features(x)
            feats[size] = (x, torch_models.pool_feature_rows(torch, f))
    for variant in VARIANTS:
        for size, (h, w, columns) in SIZES.items():
            name = f"{variant}_{size}"
            if size not in feats or (only and name not in only):
                continue
            head = torch_models.stixel_head(torch, variant, columns)
            refcommon.init_weights(head, seed=100 + VARIANTS.index(variant))
            head.eval()
            x, pooled = feats[size]
            with torch.no_grad():
                y = head(pooled)
            sd = {f"features.{k}": v for k, v in backbone.features.state_dict().items()}
            sd.update({f"classifier.{k}": v for k, v in head.state_dict().items()})
            refcommon.save(f"{out}/stixel_{variant}_weights.safetensors", sd)
            case = {"input": x, "expected": y}
            if variant == "v4":
                import numpy as np
                case["authors_d"] = torch.from_numpy(authors_depths(np, y[0]))
            refcommon.save(f"{out}/stixel_case_{name}.safetensors", case)
            print(f"{name}: {list(x.shape)} -> {list(y.shape)}")


if __name__ == "__main__":
    main()
