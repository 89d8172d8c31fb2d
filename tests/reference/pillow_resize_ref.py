"""A numpy port of Pillow's uint8 bilinear resize (libImaging/Resample.c:
precompute_coeffs, normalize_coeffs_8bpc, ImagingResampleHorizontal_8bpc /
ImagingResampleVertical_8bpc), which detectron2's ResizeTransform applies to every
input. Written from shared/reference/detectron2.md §3.2; checked bitwise against
Pillow itself by detectron2_ref.py."""
import math

import numpy as np

PRECISION_BITS = 32 - 8 - 2


def coeffs(in_size, out_size):
    """Per output index: first tap, number of taps, fixed-point weights [out, ksize]."""
    scale = in_size / out_size
    filterscale = max(scale, 1.0)
    support = 1.0 * filterscale
    ksize = int(math.ceil(support)) * 2 + 1
    first = np.zeros(out_size, np.int64)
    count = np.zeros(out_size, np.int64)
    k = np.zeros((out_size, ksize), np.int64)
    for i in range(out_size):
        center = (i + 0.5) * scale
        ss = 1.0 / filterscale
        xmin = max(int(center - support + 0.5), 0)
        xmax = min(int(center + support + 0.5), in_size) - xmin
        w = []
        for x in range(xmax):
            t = abs((x + xmin - center + 0.5) * ss)
            w.append(1.0 - t if t < 1.0 else 0.0)
        ww = sum(w)
        for x in range(xmax):
            v = w[x] / ww if ww != 0.0 else w[x]
            k[i, x] = int(-0.5 + v * (1 << PRECISION_BITS)) if v < 0 else int(0.5 + v * (1 << PRECISION_BITS))
        first[i], count[i] = xmin, xmax
    return first, count, k


def clip8(v):
    return np.where(v >= (1 << PRECISION_BITS << 8), 255, np.where(v <= 0, 0, v >> PRECISION_BITS)).astype(np.uint8)


def pass_axis0(img, out_size):
    """Resamples axis 0 of an int array [n, ...] to out_size samples."""
    first, count, k = coeffs(img.shape[0], out_size)
    src = img.astype(np.int64)
    out = np.empty((out_size,) + img.shape[1:], np.uint8)
    for i in range(out_size):
        acc = np.full(img.shape[1:], 1 << (PRECISION_BITS - 1), np.int64)
        for t in range(count[i]):
            acc += src[first[i] + t] * k[i, t]
        out[i] = clip8(acc)
    return out


def resize(img, out_h, out_w):
    """img: uint8 [H, W, C] -> uint8 [out_h, out_w, C], as PIL's resize((out_w, out_h), BILINEAR)."""
    h, w = img.shape[:2]
    out = img
    if w != out_w:  # horizontal pass first
        out = pass_axis0(out.transpose(1, 0, 2), out_w).transpose(1, 0, 2)
    if h != out_h:
        out = pass_axis0(out, out_h)
    return np.ascontiguousarray(out)
