#!/usr/bin/python3
"""Reference outputs of torchvision.ops and the detection utilities the detector
reimplements, written into --out as det_ops_<name>.safetensors:
  roi_align_<case>  'feature' [1,C,H,W], 'rois' [R,4] (x1,y1,x2,y2), 'scale' [1], 'sampling' [1],
                    'expected' [R,C,7,7]; RoIs include ones reaching outside the map and
                    ones smaller than a cell and a zero-sized one
  nms               'boxes', 'scores', 'keep' (I64) at threshold 0.5, with exact-IoU 0.5 pairs
  batched_small / batched_large  'boxes', 'scores', 'classes', 'keep' (I64) for both paths
  anchors_<case>    AnchorGenerator output for given feature and padded sizes
  decode            BoxCoder((10,10,5,5)).decode_single with deltas beyond the clamp"""
import sys

import refcommon


def main():
    out, _ = refcommon.out_dir(sys.argv[1:])
    torch = refcommon.import_torch()
    from torchvision import ops
    from torchvision.models.detection import _utils as det_utils
    from torchvision.models.detection.anchor_utils import AnchorGenerator
    from torchvision.models.detection.image_list import ImageList
    g = torch.Generator().manual_seed(5)

    for case, (c, h, w, scale, sampling) in {"s32": (19, 24, 42, 1 / 32, 2), "s4": (8, 50, 37, 0.25, 2),
                                             "adaptive": (5, 30, 30, 0.5, 0)}.items():
        feat = torch.randn((1, c, h, w), generator=g)
        img_h, img_w = h / scale, w / scale
        xy = torch.rand((60, 2), generator=g) * torch.tensor([img_w, img_h]) * 1.2 - 0.1 * torch.tensor([img_w, img_h])
        wh = torch.rand((60, 2), generator=g) * torch.tensor([img_w, img_h]) * 0.6
        tiny = torch.rand((20, 2), generator=g) * (0.5 / scale)  # smaller than one cell
        wh = torch.cat([wh, tiny])
        xy = torch.cat([xy, torch.rand((20, 2), generator=g) * torch.tensor([img_w, img_h])])
        # Beyond the map on every side.
        far = torch.tensor([[-3 / scale, -3 / scale, -0.5 / scale, -0.2 / scale],
                            [img_w - 2 / scale, img_h - 1 / scale, img_w + 4 / scale, img_h + 3 / scale],
                            [-1.5 / scale, 2 / scale, 1 / scale, img_h + 1.5 / scale],
                            [5 / scale, 4 / scale, 5 / scale, 4 / scale]])  # zero-sized
        rois = torch.cat([torch.cat([xy, xy + wh], 1), far])
        with_idx = torch.cat([torch.zeros((rois.shape[0], 1)), rois], 1)
        y = ops.roi_align(feat, with_idx, (7, 7), spatial_scale=scale, sampling_ratio=sampling, aligned=False)
        refcommon.save(f"{out}/det_ops_roi_align_{case}.safetensors",
                       {"feature": feat, "rois": rois, "scale": torch.tensor([scale], dtype=torch.float32),
                        "sampling": torch.tensor([sampling], dtype=torch.int64), "expected": y})

    # NMS: random boxes with distinct scores, plus pairs with IoU exactly 0.5 (kept:
    # suppression needs IoU > threshold) and just above it.
    xy = torch.rand((300, 2), generator=g) * 200
    boxes = torch.cat([xy, xy + 5 + torch.rand((300, 2), generator=g) * 60], 1)
    exact = torch.tensor([[0., 0., 10., 10.], [0., 0., 10., 5.], [300., 300., 310., 310.], [300., 300., 310., 305.1]])
    boxes = torch.cat([boxes, exact])
    scores = torch.randperm(boxes.shape[0], generator=g).float() / boxes.shape[0]
    scores[-4:] = torch.tensor([2.0, 1.9, 1.8, 1.7])
    keep = ops.nms(boxes, scores, 0.5)
    refcommon.save(f"{out}/det_ops_nms.safetensors", {"boxes": boxes, "scores": scores, "keep": keep})

    for name, n in (("batched_small", 400), ("batched_large", 1500)):
        xy = torch.rand((n, 2), generator=g) * 300
        boxes = torch.cat([xy, xy + 2 + torch.rand((n, 2), generator=g) * 80], 1)
        scores = torch.randperm(n, generator=g).float() / n
        classes = torch.randint(0, 3, (n,), generator=g)
        keep = ops.batched_nms(boxes, scores, classes, 0.7)
        refcommon.save(f"{out}/det_ops_{name}.safetensors",
                       {"boxes": boxes, "scores": scores, "classes": classes, "keep": keep})

    # Anchors: MobileNet's 15 per cell on 3 levels and ResNet's 3 per cell on 5 levels,
    # including the 'pool' level whose stride comes from integer division.
    mobile = ((32, 64, 128, 256, 512),) * 3
    resnet = ((32,), (64,), (128,), (256,), (512,))
    for case, sizes, padded, grids in (
            ("mobile", mobile, (768, 1344), [(24, 42), (24, 42), (12, 21)]),
            ("resnet", resnet, (800, 1344), [(200, 336), (100, 168), (50, 84), (25, 42), (13, 21)])):
        gen = AnchorGenerator(sizes, ((0.5, 1.0, 2.0),) * len(sizes))
        il = ImageList(torch.zeros((1, 3) + padded), [padded])
        feats = [torch.zeros((1, 1) + gs) for gs in grids]
        anchors = gen(il, feats)[0]
        refcommon.save(f"{out}/det_ops_anchors_{case}.safetensors",
                       {"anchors": anchors, "grids": torch.tensor(grids, dtype=torch.int64),
                        "padded": torch.tensor(padded, dtype=torch.int64)})

    ref = torch.rand((200, 2), generator=g) * 500
    ref = torch.cat([ref, ref + 1 + torch.rand((200, 2), generator=g) * 100], 1)
    deltas = torch.randn((200, 4), generator=g) * 3
    deltas[:50, 2:] = 60 * torch.rand((50, 2), generator=g) + 5  # far beyond the clamp after / 5
    coder = det_utils.BoxCoder((10.0, 10.0, 5.0, 5.0))
    decoded = coder.decode_single(deltas, ref)
    refcommon.save(f"{out}/det_ops_decode.safetensors", {"ref": ref, "deltas": deltas, "expected": decoded})
    print("detector ops references written")


if __name__ == "__main__":
    main()
