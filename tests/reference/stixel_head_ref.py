#!/usr/bin/python3
"""PyTorch reference of StixelNExT++ (torchvision ConvNeXt-Tiny features -> mean over
feature rows -> stixel head) for every head variant, written from the reference
specification (../shared/reference/stixelnext.md §1.3). Writes into --out:
  stixel_<variant>_weights.safetensors   features.* + classifier.* state_dict
  stixel_case_<variant>_<size>.safetensors   'input' [1,3,H,W], 'expected' [1,A,64,U]
                                             (v4 also 'authors_d' [64,U]: see authors_depths)
Variants: v4 (latest), v1 (local column attention), v3 (global), v2 (attention unused),
v0 (plain reduce). Sizes: fullhd (1280x1920, U = 240) and small (256x640, U = 80)."""
import sys

import refcommon

SIZES = {"small": (256, 640, 80), "fullhd": (1280, 1920, 240)}
VARIANTS = ("v4", "v1", "v3", "v2", "v0")


def make_heads(torch):
    nn = torch.nn
    from torchvision.models.convnext import LayerNorm2d

    def up(c, columns):
        return nn.Sequential(nn.Upsample(size=(1, columns), mode="nearest"), LayerNorm2d(c, eps=1e-6))

    class ColumnAttention(nn.Module):
        def __init__(self, c, local):
            super().__init__()
            self.query_layer, self.key_layer, self.value_layer = nn.Linear(c, c), nn.Linear(c, c), nn.Linear(c, c)
            self.local = local

        def forward(self, x):  # [B, C, H, W]
            b, c, h, w = x.shape
            cols = (x.squeeze(2) if self.local else x.mean(dim=2)).permute(0, 2, 1)  # [B, W, C]
            q, k, v = self.query_layer(cols), self.key_layer(cols), self.value_layer(cols)
            if self.local:
                # keys j in [i-1, i+1] clipped at the borders; scale sqrt(C) as a float32 tensor
                scores = torch.matmul(q, k.transpose(1, 2)) / torch.sqrt(torch.tensor(float(c), dtype=torch.float32))
                i = torch.arange(w)
                band = (i[:, None] - i[None, :]).abs() <= 1
                scores = scores.masked_fill(~band, float("-inf"))
            else:
                scores = torch.matmul(q, k.transpose(1, 2)) / (c ** 0.5)
            out = torch.matmul(torch.softmax(scores, dim=-1), v)  # [B, W, C]
            return out.permute(0, 2, 1).unsqueeze(2)

    class HeadV0V3(nn.Module):
        def __init__(self, c, columns, variant):
            super().__init__()
            self.variant = variant
            if variant in ("v1", "v3", "v2"):
                self.attention_layer = ColumnAttention(c, local=(variant == "v1"))
            in_ch = 2 * c if variant in ("v1", "v3") else c
            if variant == "v0":
                self.reduce = nn.Conv2d(in_ch, 192, 1)  # V0 names are found by shape
            else:
                self.channel_reduce = nn.Conv2d(in_ch, 192, 1)
            self.up = up(192, columns)

        def forward(self, f):
            if self.variant in ("v1", "v3"):
                f = torch.cat([self.attention_layer(f), f], dim=1)
            r = self.reduce(f) if self.variant == "v0" else self.channel_reduce(f)
            r = self.up(r)
            b, _, _, u = r.shape
            return torch.sigmoid(r.reshape(b, 3, 64, 1, u).squeeze(3))

    class LocalColumnMixing(nn.Module):
        def __init__(self, c):
            super().__init__()
            self.depthwise = nn.Conv2d(c, c, (1, 5), padding=(0, 2), groups=c)
            self.pointwise = nn.Conv2d(c, c, 1)

        def forward(self, x):
            return self.pointwise(torch.nn.functional.gelu(self.depthwise(x)))

    class HeadV4(nn.Module):
        def __init__(self, c, columns):
            super().__init__()
            self.local_mixing = LocalColumnMixing(c)
            self.shared_reduce = nn.Conv2d(c, 256, 1)
            self.up = up(256, columns)
            self.geometry_head = nn.Conv2d(256, 128, 1)
            self.depth_head = nn.Conv2d(256, 64, 1)
            self.probability_head = nn.Conv2d(256, 64, 1)

        def forward(self, f):
            x = f + self.local_mixing(f)
            r = self.up(self.shared_reduce(x))
            b, _, _, u = r.shape
            g = torch.sigmoid(self.geometry_head(r)).reshape(b, 2, 64, 1, u)
            d = torch.sigmoid(self.depth_head(r)).reshape(b, 1, 64, 1, u)
            p = torch.sigmoid(self.probability_head(r)).reshape(b, 1, 64, 1, u)
            return torch.cat([g, d, p], dim=1).squeeze(3)

    return HeadV0V3, HeadV4


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
    from torchvision.models import convnext_tiny
    HeadV0V3, HeadV4 = make_heads(torch)
    backbone = convnext_tiny()
    refcommon.init_weights(backbone, seed=1234)
    backbone.eval()
    feats = {}
    for size, (h, w, _) in SIZES.items():
        if only and not any(o.endswith(size) for o in only):
            continue
        x = torch.rand((1, 3, h, w), generator=torch.Generator().manual_seed(h + w)) * 255.0
        with torch.no_grad():
            f = backbone.features(x)
            feats[size] = (x, torch.nn.functional.avg_pool2d(f, (f.shape[2], 1)))
    for variant in VARIANTS:
        for size, (h, w, columns) in SIZES.items():
            name = f"{variant}_{size}"
            if size not in feats or (only and name not in only):
                continue
            head = HeadV4(768, columns) if variant == "v4" else HeadV0V3(768, columns, variant)
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
