#!/usr/bin/python3
"""PyTorch reference of StixelNExT++ (torchvision ConvNeXt-Tiny features -> mean over
feature rows -> stixel head) for every head variant (modules: weights/torch_models.py). Writes into --out:
  stixel_<variant>_weights.safetensors   features.* + classifier.* state_dict
  stixel_case_<variant>_<size>.safetensors   'input' [1,3,H,W], 'expected' [1,A,64,U]
Variants: v4 (latest), v1 (local column attention), v3 (global), v2 (attention unused),
v0 (plain reduce). Sizes: fullhd (1280x1920, U = 240) and small (256x640, U = 80)."""
import sys

import refcommon
import torch_models  # weights/, on the path through refcommon

SIZES = {"small": (256, 640, 80), "fullhd": (1280, 1920, 240)}
VARIANTS = ("v4", "v1", "v3", "v2", "v0")


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
            refcommon.save(f"{out}/stixel_case_{name}.safetensors", {"input": x, "expected": y})
            print(f"{name}: {list(x.shape)} -> {list(y.shape)}")


if __name__ == "__main__":
    main()
