#!/usr/bin/python3
"""PyTorch reference outputs of single ops, one file per case (ops_<case>.safetensors)
holding 'x' (NCHW or [M,K]), the layer's parameters and 'expected'. Shapes are
awkward on purpose: channels not a multiple of 16, widths not a multiple of any
register block, borders, 1-pixel images."""
import sys

import refcommon


def main():
    out, _ = refcommon.out_dir(sys.argv[1:])
    torch = refcommon.import_torch()
    F = torch.nn.functional
    g = torch.Generator().manual_seed(2024)

    def randn(*shape, scale=1.0):
        return torch.randn(shape, generator=g) * scale

    def save(name, **t):
        refcommon.save(f"{out}/ops_{name}.safetensors", t)

    # Linear = the GEMM with bias and each epilogue activation.
    for name, (m, k, n) in {"small": (37, 17, 33), "convnext": (130, 96, 384), "wide": (5, 600, 70)}.items():
        x, w, b = randn(m, k), randn(n, k, scale=k ** -0.5), randn(n, scale=0.05)
        save(f"linear_{name}", x=x, weight=w, bias=b, expected=F.linear(x, w, b),
             expected_gelu=F.gelu(F.linear(x, w, b)), expected_relu=F.relu(F.linear(x, w, b)),
             expected_hardswish=F.hardswish(F.linear(x, w, b)))

    # Dense convolutions: (N, Cin, H, W, Cout, k, stride, pad)
    convs = {
        "stem4x4s4": (1, 3, 37, 45, 20, 4, 4, 0),
        "down2x2s2": (2, 20, 13, 17, 36, 2, 2, 0),
        "3x3s1p1": (1, 17, 9, 11, 19, 3, 1, 1),
        "3x3s1p1_wide": (2, 64, 13, 22, 80, 3, 1, 1),
        "3x3s2p1": (1, 16, 10, 15, 24, 3, 2, 1),
        "7x7s2p3": (1, 3, 23, 29, 16, 7, 2, 3),
        "1x1": (1, 33, 5, 7, 65, 1, 1, 0),
        "1px3x3p1": (1, 5, 1, 1, 7, 3, 1, 1),
    }
    for name, (n, ci, h, w_, co, k, s, p) in convs.items():
        x, w, b = randn(n, ci, h, w_), randn(co, ci, k, k, scale=(ci * k * k) ** -0.5), randn(co, scale=0.05)
        save(f"conv_{name}", x=x, weight=w, bias=b, expected=F.conv2d(x, w, b, stride=s, padding=p),
             params=torch.tensor([k, k, s, s, p, p], dtype=torch.float32))

    # Depthwise: (N, C, H, W, kh, kw, stride, pad_h, pad_w)
    dws = {
        "7x7_c100": (1, 100, 19, 29, 7, 7, 1, 3, 3),
        "7x7_c96_b2": (2, 96, 8, 15, 7, 7, 1, 3, 3),
        "7x7_tiny": (1, 17, 2, 3, 7, 7, 1, 3, 3),
        "1x5_head": (1, 24, 1, 60, 1, 5, 1, 0, 2),
        "3x3s2_c17": (1, 17, 11, 14, 3, 3, 2, 1, 1),
        "5x5s2_c40": (1, 40, 13, 9, 5, 5, 2, 2, 2),
        "3x3s1_c33": (1, 33, 6, 7, 3, 3, 1, 1, 1),
    }
    for name, (n, c, h, w_, kh, kw, s, ph, pw) in dws.items():
        x, w, b = randn(n, c, h, w_), randn(c, 1, kh, kw, scale=(kh * kw) ** -0.5), randn(c, scale=0.05)
        save(f"dw_{name}", x=x, weight=w, bias=b,
             expected=F.conv2d(x, w, b, stride=s, padding=(ph, pw), groups=c),
             params=torch.tensor([kh, kw, s, s, ph, pw], dtype=torch.float32))

    # LayerNorm over channels (ConvNeXt's LayerNorm2d and nn.LayerNorm), eps 1e-6.
    for name, (m, c, shift) in {"c96": (301, 96, 0.0), "c100_shifted": (64, 100, 20.0), "c5": (9, 5, 0.0)}.items():
        x, gamma, beta = randn(m, c) + shift, 1 + randn(c, scale=0.2), randn(c, scale=0.1)
        # PyTorch's fp32 result carries its own rounding (its error grows with |mean|/std),
        # so the exact value (float64) is stored too.
        save(f"layernorm_{name}", x=x, weight=gamma, bias=beta,
             expected=F.layer_norm(x, (c,), gamma, beta, eps=1e-6),
             expected64=F.layer_norm(x.double(), (c,), gamma.double(), beta.double(), eps=1e-6).float())

    # Element-wise activations on a sweep including large magnitudes.
    x = torch.cat([torch.linspace(-12, 12, 4801), randn(3000, scale=3.0), torch.tensor([0.0, -0.0, 1e-30, -1e-30, 80.0, -80.0])])
    save("act", x=x, gelu=F.gelu(x), sigmoid=torch.sigmoid(x), relu=F.relu(x),
         hardswish=F.hardswish(x), hardsigmoid=F.hardsigmoid(x))
    print("ops references written")


if __name__ == "__main__":
    main()
