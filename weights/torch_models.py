"""The PyTorch modules roadnn's models correspond to, built in one place.

Used by the reference scripts (tests/reference/*.py) and scripts/torch_dump.py, so the
module trees (and with them the state_dict keys and named_modules() names) are the
same everywhere:
  convnext(torch, name)              torchvision convnext_tiny / _small / _base
  convnext_from_widths(torch, ...)   any ConvNeXt features configuration
  stixel_heads(torch)                (HeadV0V3, HeadV4): the StixelNExT++ head variants,
                                     written from ../shared/reference/stixelnext.md §1.3
  stixelnext(torch, features, head)  features.* (backbone), avgpool, classifier.* (head)
  detector(torch, builder, classes)  torchvision's Faster R-CNN constructors, untrained
torch is passed in (never imported here) so that importing this module has no side
effects and callers keep their own install hint.
"""

CONVNEXT_BUILDERS = ("convnext_tiny", "convnext_small", "convnext_base")
DETECTOR_BUILDERS = ("fasterrcnn_resnet50_fpn", "fasterrcnn_mobilenet_v3_large_fpn",
                     "fasterrcnn_mobilenet_v3_large_320_fpn")
STIXEL_HEAD_VARIANTS = ("v4", "v1", "v3", "v2", "v0")


def convnext(torch, name):
    """torchvision's ConvNeXt `name` (untrained; run model.features(x) for nnrun's output)."""
    from torchvision.models import convnext as cn
    if name not in CONVNEXT_BUILDERS:
        raise ValueError(f"unknown ConvNeXt '{name}' (expected one of {', '.join(CONVNEXT_BUILDERS)})")
    return getattr(cn, name)()


def convnext_from_widths(torch, widths, depths):
    """A ConvNeXt with stage widths/depths of one's choice (stochastic depth 0, as in eval)."""
    from functools import partial
    from torchvision.models import convnext as cn
    cfg = [cn.CNBlockConfig(widths[i], widths[i + 1] if i + 1 < len(widths) else None, depths[i])
           for i in range(len(widths))]
    return cn.ConvNeXt(cfg, stochastic_depth_prob=0.0, norm_layer=partial(cn.LayerNorm2d, eps=1e-6))


def stixel_heads(torch):
    """The head classes (HeadV0V3, HeadV4); HeadV0V3(c, columns, variant), HeadV4(c, columns)."""
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


def stixel_head(torch, variant, columns, channels=768):
    """A head of `variant` (v0..v4) predicting `columns` columns from `channels` features."""
    HeadV0V3, HeadV4 = stixel_heads(torch)
    if variant not in STIXEL_HEAD_VARIANTS:
        raise ValueError(f"unknown StixelNExT++ head '{variant}' (expected one of v0..v4)")
    return HeadV4(channels, columns) if variant == "v4" else HeadV0V3(channels, columns, variant)


def pool_feature_rows(torch, f):
    """StixelNExT++'s mean over the feature rows: [N, C, H, W] -> [N, C, 1, W]."""
    return torch.nn.functional.avg_pool2d(f, (f.shape[2], 1))


def stixelnext(torch, features, head):
    """The authors' module tree: features.* (ConvNeXt-Tiny's features), avgpool (the mean
    over all feature rows), classifier.* (head); forward: classifier(avgpool(features(x)))
    -> [N, A, 64, U]."""

    class AvgPoolRows(torch.nn.Module):
        """The authors' `avgpool`, AvgPool2d((rows, 1)) with `rows` hard-coded for their
        input height (../shared/reference/stixelnext.md §1.1); here the kernel is the
        height of whatever comes in, so any input size runs. A module (not a function
        call) so that named_modules() has `avgpool`, as the authors' model does and as
        nnrun --dump names it; the same avg_pool2d call as pool_feature_rows, so the
        outputs are the same bits as the reference scripts'."""

        def forward(self, f):
            return pool_feature_rows(torch, f)

    class StixelNExT(torch.nn.Module):
        def __init__(self):
            super().__init__()
            self.features = features
            self.avgpool = AvgPoolRows()
            self.classifier = head

        def forward(self, x):
            return self.classifier(self.avgpool(self.features(x)))

    return StixelNExT()


def detector(torch, builder, num_classes):
    """torchvision's Faster R-CNN `builder` without pretrained weights, with its default
    eval settings (min_size/max_size, score and NMS thresholds), as the tests run it."""
    from torchvision.models import detection
    if builder not in DETECTOR_BUILDERS:
        raise ValueError(f"unknown detector '{builder}' (expected one of {', '.join(DETECTOR_BUILDERS)})")
    return getattr(detection, builder)(weights=None, weights_backbone=None, num_classes=num_classes)
