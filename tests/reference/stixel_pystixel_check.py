"""Reads a .stx1 written by `stixelnext` (defaults: image embedded) the way
pyStixel-lib does, with python3-protobuf, and checks what its users rely on.
pyStixel-lib itself is not installable here, so its formulas are written out
below from its source (MarcelVSHNS/pyStixel-lib, stixel/utils/transformation.py
and visualization.py):

  * every field its reader, convert_to_point_cloud and draw_stixels_on_image
    touch is there: stixels with u, vT, vB, d, width, confidence; context.name;
    calibration K (9), T (16), width, height; the image, which PIL opens, of the
    calibration's size, and which draw_stixels_on_image's steps (convert RGBA,
    rectangles far to near, alpha_composite) draw on;
  * with --points FILE.ply: our point cloud equals convert_to_point_cloud(world,
    return_rgb_values=True) (float32 [u, v, d, 1] rows, u and v times d in
    float32, inverse(K4 @ T) in float64) within --tol metres, point for point,
    with the same colours (PIL getpixel at (u, v)), the owning stixel index and,
    when the PLY has them, the stixels' cluster labels.
  * --expect-image FILE: the embedded bytes are that file's bytes.
Exit status 1 with a one-line message on the first failure."""
import io
import sys

import stixel_refutil as ru

np = ru.import_numpy()


def fail(msg):
    sys.exit("error: " + msg)


def read_ply(path):
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    if header[0] != "ply" or header[1] != "format binary_little_endian 1.0":
        fail("%s: not a binary little-endian PLY" % path)
    count, props = 0, []
    for line in header:
        w = line.split()
        if w[:2] == ["element", "vertex"]:
            count = int(w[2])
        elif w[0] == "property":
            props.append((w[2], {"float": "<f4", "uchar": "u1", "int": "<i4"}[w[1]]))
    rows = np.frombuffer(data[end:], dtype=np.dtype(props), count=count)
    if end + rows.nbytes != len(data):
        fail("%s: %d bytes after the header, %d vertices need %d" % (path, len(data) - end, count, rows.nbytes))
    return rows


def pystixel_point_cloud(world, img):
    """convert_to_point_cloud(world, return_rgb_values=True), slanted_angle_rad=None."""
    n = sum(max(0, s.vB - s.vT) for s in world.stixel)
    mtx = np.empty((n, 4), dtype=np.float32)
    colors = np.empty((n, 3), dtype=np.float32)
    owner = np.empty(n, dtype=np.int32)
    idx = 0
    for i, s in enumerate(world.stixel):
        for v in range(s.vT, s.vB):
            mtx[idx] = [s.u, v, s.d, 1.0]
            r, g, b = img.getpixel((s.u, v))
            colors[idx] = [r / 255.0, g / 255.0, b / 255.0]
            owner[idx] = i
            idx += 1
    mtx[:, :2] *= mtx[:, 2:3]
    k_exp = np.eye(4)
    k_exp[:3, :3] = np.array(world.context.calibration.K).reshape(3, 3)
    P = k_exp @ np.array(world.context.calibration.T).reshape(4, 4)
    pts = (np.linalg.inv(P) @ mtx.T).T[:, 0:3]
    return pts, colors, owner


def draw_stixels_on_image(world, Image, ImageDraw, alpha=0.5, prob=0.5):
    """Its steps with a fixed colour (what needs the fields, not the colour maps)."""
    img = Image.open(io.BytesIO(world.image))
    image = img.convert("RGBA")
    overlay = Image.new("RGBA", image.size, (0, 0, 0, 0))
    draw = ImageDraw.Draw(overlay)
    drawn = 0
    for s in sorted(world.stixel, key=lambda x: x.d, reverse=True):
        if s.confidence >= prob:
            off = s.width // 2
            left, right = max(0, int(s.u - off)), min(image.width - 1, int(s.u + off))
            top, bottom = max(0, min(s.vT, s.vB)), min(image.height - 1, max(s.vT, s.vB))
            if right <= left or bottom <= top:
                continue
            draw.rectangle([left, top, right, bottom], fill=(255, 0, 0, int(alpha * 255)))
            drawn += 1
    return Image.alpha_composite(image, overlay).convert("RGB"), drawn


def main(argv):
    a = ru.args(argv, [("--pb-dir", dict(required=True)), ("--input", dict(required=True)),
                       ("--points", dict(default=None)), ("--expect-image", dict(default=None)),
                       ("--tol", dict(type=float, default=1e-5))], need_out=False)
    try:
        from PIL import Image, ImageDraw
    except ImportError as e:
        fail("Pillow is needed: apt-get install -y python3-pil (%s)" % e)
    pb = ru.protobuf_module(a.pb_dir)
    world = pb.StixelWorld()
    world.ParseFromString(open(a.input, "rb").read())
    c = world.context
    if not world.stixel:
        fail("%s: no stixels" % a.input)
    if not c.name:
        fail("%s: context.name is empty (pyStixel-lib's save names the file after it)" % a.input)
    if len(c.calibration.K) != 9 or len(c.calibration.T) != 16:
        fail("%s: calibration K has %d values, T %d (convert_to_point_cloud reshapes them to 3x3 and 4x4)"
             % (a.input, len(c.calibration.K), len(c.calibration.T)))
    if c.calibration.width <= 0 or c.calibration.height <= 0:
        fail("%s: calibration width/height missing" % a.input)
    if any(s.width <= 0 for s in world.stixel):
        fail("%s: a stixel without width" % a.input)
    if not world.image:
        fail("%s: no embedded image (draw_stixels_on_image(world) raises ValueError)" % a.input)
    if a.expect_image and world.image != open(a.expect_image, "rb").read():
        fail("%s: the embedded image is not the bytes of %s" % (a.input, a.expect_image))
    img = Image.open(io.BytesIO(world.image))
    if img.size != (c.calibration.width, c.calibration.height):
        fail("%s: embedded image is %dx%d, the stixels' frame (calibration) %dx%d"
             % (a.input, img.size[0], img.size[1], c.calibration.width, c.calibration.height))
    if img.mode != "RGB":
        fail("%s: embedded image mode %s, convert_to_point_cloud's getpixel needs RGB" % (a.input, img.mode))
    picture, drawn = draw_stixels_on_image(world, Image, ImageDraw, prob=0.0)
    if picture.size != img.size or drawn == 0:
        fail("%s: draw_stixels_on_image drew %d stixels" % (a.input, drawn))

    if a.points:
        rows = read_ply(a.points)
        # pyStixel-lib's getpixel raises for rows outside the image; our file clamps
        # them to the edge: compare only stixels inside the image.
        pts, colors, owner = pystixel_point_cloud_inside(world, img)
        names = rows.dtype.names
        ours_inside = rows[np.isin(rows["stixel"], np.unique(owner))] if len(owner) else rows[:0]
        if len(ours_inside) != len(pts):
            fail("%s: %d points of in-image stixels, pyStixel-lib has %d" % (a.points, len(ours_inside), len(pts)))
        if not np.array_equal(ours_inside["stixel"], owner):
            fail("%s: point order or stixel indices differ" % a.points)
        xyz = np.stack([ours_inside["x"], ours_inside["y"], ours_inside["z"]], axis=1).astype(np.float64)
        err = np.abs(xyz - pts).max() if len(pts) else 0.0
        if not err <= a.tol:
            fail("%s: coordinates differ from convert_to_point_cloud by up to %g m (tolerance %g)"
                 % (a.points, err, a.tol))
        rgb = np.stack([ours_inside["red"], ours_inside["green"], ours_inside["blue"]], axis=1) / 255.0
        if not np.array_equal(rgb.astype(np.float32), colors):
            fail("%s: colours differ from getpixel on the embedded image" % a.points)
        if "cluster" in names:
            want = np.array([world.stixel[i].cluster for i in owner], dtype=np.int32)
            if not np.array_equal(ours_inside["cluster"], want):
                fail("%s: cluster labels differ from the stixels'" % a.points)
        print("points: %d compared, max error %.3g m" % (len(pts), err))
    print("%s: %d stixels, image %dx%d %s, every pyStixel-lib field present"
          % (a.input, len(world.stixel), img.size[0], img.size[1], img.format))


def pystixel_point_cloud_inside(world, img):
    keep = [i for i, s in enumerate(world.stixel)
            if 0 <= s.u < img.size[0] and s.vT >= 0 and s.vB <= img.size[1]]
    sub = type(world)()
    sub.CopyFrom(world)
    del sub.stixel[:]
    for i in keep:
        sub.stixel.add().CopyFrom(world.stixel[i])
    pts, colors, owner = pystixel_point_cloud(sub, img)
    return pts, colors, np.array(keep, dtype=np.int32)[owner] if len(owner) else owner


if __name__ == "__main__":
    main(sys.argv[1:])
