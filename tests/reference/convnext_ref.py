#!/usr/bin/python3
"""Reference outputs of torchvision's ConvNeXt features for the engine's tests.

Writes into --out:
  convnext_tiny_weights.safetensors    full convnext_tiny state_dict (features.* and classifier.*)
  convnext_small_cfg_weights.safetensors   an odd-width 4-stage config (features.* only)
  convnext_case_<name>.safetensors     'input' [N,3,H,W] and 'expected' (model.features(input))
Cases: tiny_224 (1x3x224x224), tiny_odd (1x3x200x328), tiny_batch2 (2x3x224x224),
tiny_fullhd (1x3x1280x1920, raw 0..255 pixels as StixelNExT++ feeds them), tiny_small
(1x3x64x96), odd_cfg (1x3x100x132); with ROADNN_TEST_SIZES=small only the small ones
(SMALL_CASES). Pass case names to limit what is generated."""
import sys
import time
import zlib

import refcommon
import torch_models  # weights/, on the path through refcommon

CASES = {
    # name: (weights, (N, C, H, W), input kind)
    "tiny_224": ("tiny", (1, 3, 224, 224), "normal"),
    "tiny_odd": ("tiny", (1, 3, 200, 328), "normal"),
    "tiny_batch2": ("tiny", (2, 3, 224, 224), "normal"),
    "tiny_fullhd": ("tiny", (1, 3, 1280, 1920), "raw255"),
    "tiny_small": ("tiny", (1, 3, 64, 96), "normal"),
    "odd_cfg": ("odd", (1, 3, 100, 132), "normal"),
}
SMALL_CASES = ("tiny_small", "odd_cfg")


def build(torch, kind):
    if kind == "tiny":
        model = torch_models.convnext(torch, "convnext_tiny")
    else:
        # Widths that are not multiples of 16, to exercise every kernel tail.
        model = torch_models.convnext_from_widths(torch, [20, 36, 52, 100], [1, 1, 2, 1])
    refcommon.init_weights(model, seed=1234 if kind == "tiny" else 99)
    return model.eval()


def main():
    out, only = refcommon.out_dir(sys.argv[1:])
    torch = refcommon.import_torch()
    models = {}
    for name, (kind, shape, inp) in CASES.items():
        if (only and name not in only) or (refcommon.small_sizes() and name not in SMALL_CASES):
            continue
        if kind not in models:
            models[kind] = build(torch, kind)
            sd = models[kind].state_dict()
            if kind != "tiny":
                sd = {k: v for k, v in sd.items() if k.startswith("features.")}
            refcommon.save(f"{out}/convnext_{'tiny' if kind == 'tiny' else 'small_cfg'}_weights.safetensors", sd)
        g = torch.Generator().manual_seed(zlib.crc32(name.encode()))
        x = torch.randn(shape, generator=g) if inp == "normal" else torch.rand(shape, generator=g) * 255.0
        t0 = time.time()
        with torch.no_grad():
            y = models[kind].features(x)
        print(f"{name}: input {list(shape)} -> {list(y.shape)} in {time.time() - t0:.2f} s")
        refcommon.save(f"{out}/convnext_case_{name}.safetensors", {"input": x, "expected": y})


if __name__ == "__main__":
    main()
