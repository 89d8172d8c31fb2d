#!/usr/bin/python3
"""Reference outputs of torchvision 0.14's Faster R-CNN for the detector tests.

Writes into --out:
  det_<model>_weights.safetensors   state_dict with seeded random weights (3 classes),
                                    batch-norm running statistics randomised too
  det_<model>_<case>.safetensors    'input' [1,3,H,W] in [0,1]; 'transformed' [1,3,Hp,Wp];
                                    'proposals' [P,4]; 'boxes' [K,4], 'scores' [K], 'labels' [K];
                                    the small case also 'transform_size' [min_size, max_size]
Cases: 720p and odd (457x613) at each model's own transform size (800 / 1333, 320 / 640 for
the 320 model); small (180x240 upscaled to 240x320 by a transform of min_size 240, max_size
320: the same weights and code on a small image). ROADNN_TEST_SIZES=small: only small.
Random weights make the RPN and class scores arbitrary; calibrate() spreads them so the
default thresholds (RPN 0.05, box 0.05) leave hundreds of proposals and real detections."""
import sys
import zlib

import refcommon
import torch_models  # weights/, on the path through refcommon

MODELS = {
    "mnv3": "fasterrcnn_mobilenet_v3_large_fpn",
    "mnv3_320": "fasterrcnn_mobilenet_v3_large_320_fpn",
    "r50": "fasterrcnn_resnet50_fpn",
}
CASES = {"720p": (720, 1280), "odd": (457, 613), "small": (180, 240)}
# Cases run with another transform size than the model's default: (min_size, max_size).
TRANSFORM_SIZES = {"small": (240, 320)}


def build(torch, builder, seed, num_classes=3):
    """torchvision's detector `builder` with seeded random weights (the tests use 3 classes)."""
    model = torch_models.detector(torch, builder, num_classes)
    refcommon.init_weights(model, seed)
    g = torch.Generator().manual_seed(seed + 1)
    with torch.no_grad():
        for m in model.modules():
            if isinstance(m, torch.nn.BatchNorm2d):
                m.running_mean.copy_(0.1 * torch.randn(m.running_mean.shape, generator=g))
                m.running_var.copy_(torch.rand(m.running_var.shape, generator=g) + 0.5)
    return model.eval()


def calibrate(torch, model, x):
    """At the foundation's scales the head outputs are either tiny (MobileNet: std ~0.1,
    every score near one value) or huge (ResNet-50: sigmoid and softmax saturate to
    exactly 1.0, so top-k and NMS order hinge on ties). Rescaling the four output
    layers to a fixed output spread on this input makes proposals and detections real,
    distinct decisions: logit std 2, delta std 0.3."""
    targets = (("rpn.head.cls_logits", 2.0), ("rpn.head.bbox_pred", 0.3),
               ("roi_heads.box_predictor.cls_score", 2.0), ("roi_heads.box_predictor.bbox_pred", 0.3))
    for stage in (targets[:2], targets[2:]):  # the box head sees the calibrated RPN's proposals
        seen = {}
        hooks = [model.get_submodule(name).register_forward_hook(
            lambda m, i, o, name=name: seen.setdefault(name, []).append(o.detach().flatten()))
            for name, _ in stage]
        with torch.no_grad():
            model([x[0]])
        for h in hooks:
            h.remove()
        with torch.no_grad():
            for name, target in stage:
                k = target / float(torch.cat(seen[name]).std())
                layer = model.get_submodule(name)
                layer.weight.mul_(k)
                layer.bias.mul_(k)


def make_input(torch, case, h, w):
    g = torch.Generator().manual_seed(zlib.crc32(case.encode()))
    # A smooth image (upsampled noise) plus fine noise: features at every scale.
    coarse = torch.rand((1, 3, h // 16 + 1, w // 16 + 1), generator=g)
    x = torch.nn.functional.interpolate(coarse, size=(h, w), mode="bilinear", align_corners=False)
    return (0.8 * x + 0.2 * torch.rand((1, 3, h, w), generator=g)).clamp(0, 1)


def main():
    out, only = refcommon.out_dir(sys.argv[1:])
    torch = refcommon.import_torch()
    for key, builder in MODELS.items():
        if only and key not in only:
            continue
        model = build(torch, builder, seed=4242)
        calibrate(torch, model, make_input(torch, "720p", *CASES["720p"]))
        refcommon.save(f"{out}/det_{key}_weights.safetensors", model.state_dict())
        default_sizes = (model.transform.min_size, model.transform.max_size)
        for case, (h, w) in CASES.items():
            if refcommon.small_sizes() and case not in TRANSFORM_SIZES:
                continue
            x = make_input(torch, case, h, w)
            sizes = TRANSFORM_SIZES.get(case)
            model.transform.min_size, model.transform.max_size = ((sizes[0],), sizes[1]) if sizes else default_sizes
            with torch.no_grad():
                images, _ = model.transform([x[0]])
                features = model.backbone(images.tensors)
                proposals, _ = model.rpn(images, features)
                det, _ = model.roi_heads(features, proposals, images.image_sizes)
                det = model.transform.postprocess(det, images.image_sizes, [(h, w)])[0]
                full = model([x[0]])[0]
            assert torch.equal(full["boxes"], det["boxes"]), "staged run differs from model()"
            s = det["scores"]
            print(f"{key}/{case}: transformed {list(images.tensors.shape)}, {proposals[0].shape[0]} proposals, "
                  f"{s.shape[0]} detections, scores {float(s.min()) if len(s) else 0:.3f}..{float(s.max()) if len(s) else 0:.3f}")
            tensors = {"input": x, "transformed": images.tensors, "proposals": proposals[0],
                       "boxes": det["boxes"], "scores": det["scores"], "labels": det["labels"]}
            if sizes:
                tensors["transform_size"] = torch.tensor(sizes, dtype=torch.int64)
            refcommon.save(f"{out}/det_{key}_{case}.safetensors", tensors)


if __name__ == "__main__":
    main()
