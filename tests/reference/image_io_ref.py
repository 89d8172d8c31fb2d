"""Reference pixels for apps/common/image_io (tests/apps/reftest_image_io.cpp).

Writes PNG files (8-bit gray / gray+alpha / RGB / RGBA / palette / palette+tRNS /
gray+tRNS / RGB+tRNS / 1-bit gray / 16-bit gray / 16-bit RGB / interlaced 8- and
16-bit) and JPEG files (baseline 4:2:0, progressive 4:4:4, gray) into OUT/image_io/,
decodes them with Pillow, converts the pixels to every requested channel count the way
stb_image did (and image_io does), and writes the raw results plus manifest.txt:
    file want keep16 width height channels bit_depth raw_file tolerance
Pillow cannot write 16-bit RGB or interlaced PNGs, so those come from the small writer
below; Pillow still decodes them and must agree with the source array.

    image_io_ref.py --out DIR          write the references
    image_io_ref.py --verify DIR       check that Pillow reads every DIR/enc_WxHxC.png
                                       exactly as the raw pixels in DIR/enc_WxHxC.raw
"""
import os
import struct
import sys
import zlib

INSTALL_HINT = ("the image references need Pillow and numpy for /usr/bin/python3: "
                "apt-get install -y python3-pil python3-numpy")
try:
    import numpy as np
    from PIL import Image
except ImportError as e:
    sys.exit("error: %s (%s)" % (INSTALL_HINT, e))


# ---- a minimal PNG writer (any color type, 8/16 bits, optional Adam7) ----------------------

def _chunk(kind, data):
    body = kind + data
    return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)


def _filter_rows(rows, bpp):
    """Rows of bytes -> filtered scanlines, cycling filters None, Sub, Up, Average, Paeth."""
    out = bytearray()
    prev = bytes(len(rows[0])) if rows else b""
    for i, row in enumerate(rows):
        f = i % 5
        line = bytearray(len(row))
        for x in range(len(row)):
            a = row[x - bpp] if x >= bpp else 0
            b = prev[x]
            c = prev[x - bpp] if x >= bpp else 0
            if f == 0:
                p = 0
            elif f == 1:
                p = a
            elif f == 2:
                p = b
            elif f == 3:
                p = (a + b) // 2
            else:
                pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                p = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
            line[x] = (row[x] - p) & 0xFF
        out.append(f)
        out += line
        prev = row
    return bytes(out)


def write_png(path, arr, color_type, interlace=False, trns=None):
    """arr: (H, W, n) uint8 or uint16 (samples, palette indices for color type 3)."""
    h, w, n = arr.shape
    depth = 16 if arr.dtype == np.uint16 else 8
    bpp = n * depth // 8
    be = arr.astype(">u2") if depth == 16 else arr

    def rows_of(sub):
        return [sub[y].tobytes() for y in range(sub.shape[0])]

    if interlace:
        raw = b""
        for x0, y0, dx, dy in ((0, 0, 8, 8), (4, 0, 8, 8), (0, 4, 4, 8), (2, 0, 4, 4), (0, 2, 2, 4),
                               (1, 0, 2, 2), (0, 1, 1, 2)):
            sub = be[y0::dy, x0::dx]
            if sub.shape[0] and sub.shape[1]:
                raw += _filter_rows(rows_of(sub), bpp)
    else:
        raw = _filter_rows(rows_of(be), bpp)
    png = b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, depth, color_type, 0, 0,
                                                               1 if interlace else 0))
    if trns is not None:
        png += _chunk(b"tRNS", trns)
    png += _chunk(b"IDAT", zlib.compress(raw, 6)) + _chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(png)


# ---- stb's conversions ----------------------------------------------------------------------

def stb_convert(native, want):
    """native (H, W, n) -> want channels, as stbi__convert_format(16)."""
    n = native.shape[2]
    if want == 0 or want == n:
        return native
    dt = native.dtype
    opaque = np.full(native.shape[:2], 0xFFFF if dt == np.uint16 else 0xFF, dtype=dt)
    src = native.astype(np.int64)

    def y():
        return ((src[..., 0] * 77 + src[..., 1] * 150 + src[..., 2] * 29) >> 8).astype(dt)

    g = native[..., 0]
    if n == 1:
        ch = {2: [g, opaque], 3: [g, g, g], 4: [g, g, g, opaque]}[want]
    elif n == 2:
        ch = {1: [g], 3: [g, g, g], 4: [g, g, g, native[..., 1]]}[want]
    elif n == 3:
        ch = {1: [y()], 2: [y(), opaque], 4: [native[..., 0], native[..., 1], native[..., 2], opaque]}[want]
    else:
        ch = {1: [y()], 2: [y(), native[..., 3]], 3: [native[..., 0], native[..., 1], native[..., 2]]}[want]
    return np.stack(ch, axis=2)


def pil_native(path):
    """Pillow's decode of a PNG in the layout libpng/stb deliver (palette and tRNS expanded)."""
    im = Image.open(path)
    im.load()
    if im.mode == "P":
        im = im.convert("RGBA" if "transparency" in im.info else "RGB")
    a = np.asarray(im)
    if im.mode == "1":
        a = a.astype(np.uint8) * 255
    if im.mode in ("I", "I;16", "I;16B"):
        a = a.astype(np.uint16)
    if a.ndim == 2:
        a = a[:, :, None]
    t = im.info.get("transparency")
    if im.mode in ("L", "RGB") and t is not None:  # gray / RGB tRNS -> alpha, as libpng does
        key = np.array(t if isinstance(t, tuple) else (t,), dtype=a.dtype)
        alpha = np.where(np.all(a == key, axis=2), 0, 255).astype(a.dtype)
        a = np.concatenate([a, alpha[:, :, None]], axis=2)
    return a


def smooth_image(h, w, seed):
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:h, 0:w]
    base = np.stack([xx * 255 / max(w - 1, 1), yy * 255 / max(h - 1, 1), (xx + yy) * 127 / max(w + h - 2, 1)], 2)
    return np.clip(base + rng.normal(0, 12, base.shape), 0, 255).astype(np.uint8)


def main_out(out):
    d = os.path.join(out, "image_io")
    os.makedirs(d, exist_ok=True)
    rng = np.random.default_rng(12)
    h, w = 23, 37
    rgb = rng.integers(0, 256, (h, w, 3), dtype=np.uint8)
    rgb[:5, :5] = (10, 20, 30)  # a known colour for the tRNS cases
    gray = rng.integers(0, 256, (h, w), dtype=np.uint8)
    gray[:5, :5] = 77
    alpha = rng.integers(0, 256, (h, w), dtype=np.uint8)
    g16 = rng.integers(0, 65536, (h, w), dtype=np.uint16)
    rgb16 = rng.integers(0, 65536, (h, w, 3), dtype=np.uint16)

    png = {}  # name -> source array in native layout (None: trust Pillow's decode)
    Image.fromarray(gray, "L").save(os.path.join(d, "gray8.png"))
    png["gray8.png"] = gray[:, :, None]
    Image.fromarray(np.dstack([gray, alpha]), "LA").save(os.path.join(d, "ga8.png"))
    png["ga8.png"] = np.dstack([gray, alpha])
    Image.fromarray(rgb, "RGB").save(os.path.join(d, "rgb8.png"))
    png["rgb8.png"] = rgb
    Image.fromarray(np.dstack([rgb, alpha]), "RGBA").save(os.path.join(d, "rgba8.png"))
    png["rgba8.png"] = np.dstack([rgb, alpha])
    pal = Image.fromarray(rgb, "RGB").quantize(colors=50, method=Image.Quantize.MEDIANCUT)
    pal.save(os.path.join(d, "palette.png"))
    png["palette.png"] = np.asarray(pal.convert("RGB"))
    pal.save(os.path.join(d, "palette_trns.png"), transparency=int(np.asarray(pal)[0, 0]))
    png["palette_trns.png"] = None
    Image.fromarray(gray, "L").save(os.path.join(d, "gray8_trns.png"), transparency=77)
    png["gray8_trns.png"] = np.dstack([gray, np.where(gray == 77, 0, 255).astype(np.uint8)])
    Image.fromarray(rgb, "RGB").save(os.path.join(d, "rgb8_trns.png"), transparency=(10, 20, 30))
    png["rgb8_trns.png"] = np.dstack([rgb, np.where(np.all(rgb == (10, 20, 30), axis=2), 0, 255).astype(np.uint8)])
    Image.fromarray(gray > 127).save(os.path.join(d, "gray1.png"))
    png["gray1.png"] = np.where(gray > 127, 255, 0).astype(np.uint8)[:, :, None]
    Image.fromarray(g16, "I;16").save(os.path.join(d, "gray16.png"))
    png["gray16.png"] = g16[:, :, None]
    write_png(os.path.join(d, "rgb16.png"), rgb16, 2)
    png["rgb16.png"] = rgb16
    write_png(os.path.join(d, "rgba16.png"), np.dstack([rgb16, g16]), 6)
    png["rgba16.png"] = np.dstack([rgb16, g16])
    write_png(os.path.join(d, "rgb8_interlaced.png"), rgb, 2, interlace=True)
    png["rgb8_interlaced.png"] = rgb
    write_png(os.path.join(d, "gray16_interlaced.png"), g16[:, :, None], 0, interlace=True)
    png["gray16_interlaced.png"] = g16[:, :, None]
    write_png(os.path.join(d, "ga8_interlaced.png"), np.dstack([gray, alpha])[:11, :13], 4, interlace=True)
    png["ga8_interlaced.png"] = np.dstack([gray, alpha])[:11, :13]

    lines = []

    def emit(name, want, keep16, arr, tol):
        raw = "%s.w%d.k%d.raw" % (name, want, keep16)
        data = arr.astype("<u2").tobytes() if arr.dtype == np.uint16 else arr.tobytes()
        with open(os.path.join(d, raw), "wb") as f:
            f.write(data)
        depth = 16 if arr.dtype == np.uint16 else 8
        lines.append("%s %d %d %d %d %d %d %s %d" % (name, want, keep16, arr.shape[1], arr.shape[0], arr.shape[2],
                                                     depth, raw, tol))

    for name, src in png.items():
        native = pil_native(os.path.join(d, name))
        if src is not None:
            # Pillow reduces 16-bit RGB(A) to 8 bits (high byte) on its own.
            expect = (src >> 8).astype(np.uint8) if native.dtype == np.uint8 and src.dtype == np.uint16 else src
            if native.shape != expect.shape or not np.array_equal(native, expect):
                sys.exit("error: Pillow's decode of %s differs from its source" % name)
            native = src
        for want in range(5):
            conv = stb_convert(native, want)
            if conv.dtype == np.uint16:
                emit(name, want, 1, conv, 0)
                emit(name, want, 0, (conv >> 8).astype(np.uint8), 0)
            else:
                emit(name, want, 0, conv, 0)
        if native.dtype == np.uint8:
            emit(name, 0, 1, native, 0)  # keep16 leaves 8-bit files 8-bit

    # JPEG: Pillow decodes with the same libjpeg-turbo and default settings (islow IDCT,
    # fancy upsampling), so the pixels must match exactly (tolerance 0).
    img = smooth_image(48, 64, 3)
    Image.fromarray(img, "RGB").save(os.path.join(d, "baseline420.jpg"), quality=90, subsampling=2)
    Image.fromarray(img, "RGB").save(os.path.join(d, "progressive444.jpg"), quality=95, subsampling=0,
                                     progressive=True)
    Image.fromarray(img[..., 1], "L").save(os.path.join(d, "gray.jpg"), quality=85)
    for name in ("baseline420.jpg", "progressive444.jpg", "gray.jpg"):
        path = os.path.join(d, name)
        im = Image.open(path)
        im.load()
        native = np.asarray(im)
        if native.ndim == 2:
            native = native[:, :, None]
        ycc = None
        if im.mode == "RGB":  # gray wanted: libjpeg's Y plane, as stb took it
            im2 = Image.open(path)
            im2.draft("YCbCr", im2.size)
            im2.load()
            if im2.mode != "YCbCr" or im2.size != im.size:
                sys.exit("error: Pillow did not decode %s as YCbCr" % name)
            ycc = np.asarray(im2)[:, :, :1]
        for want in range(5):
            if want in (1, 2) and ycc is not None:
                conv = stb_convert(ycc, want)
            else:
                conv = stb_convert(native, want)
            emit(name, want, 0, conv, 0)

    with open(os.path.join(d, "manifest.txt.tmp"), "w") as f:
        f.write("\n".join(lines) + "\n")
    os.replace(os.path.join(d, "manifest.txt.tmp"), os.path.join(d, "manifest.txt"))
    print("image_io_ref: %d cases in %s" % (len(lines), d))


def main_verify(d):
    modes = {1: "L", 2: "LA", 3: "RGB", 4: "RGBA"}
    checked = 0
    for name in sorted(os.listdir(d)):
        if not (name.startswith("enc_") and name.endswith(".png")):
            continue
        w, h, c = (int(v) for v in name[4:-4].split("x"))
        im = Image.open(os.path.join(d, name))
        im.load()
        if im.size != (w, h) or im.mode != modes[c]:
            sys.exit("error: %s: Pillow reads %s %dx%d, expected %s %dx%d" % (name, im.mode, im.size[0], im.size[1],
                                                                           modes[c], w, h))
        with open(os.path.join(d, name[:-4] + ".raw"), "rb") as f:
            raw = f.read()
        if np.asarray(im).tobytes() != raw:
            sys.exit("error: %s: Pillow's pixels differ from the encoded ones" % name)
        checked += 1
    if checked == 0:
        sys.exit("error: no enc_*.png in %s" % d)
    print("image_io_ref: Pillow read %d PNGs exactly" % checked)


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--out":
        main_out(sys.argv[2])
    elif len(sys.argv) == 3 and sys.argv[1] == "--verify":
        main_verify(sys.argv[2])
    else:
        sys.exit("usage: image_io_ref.py --out DIR | --verify DIR")
