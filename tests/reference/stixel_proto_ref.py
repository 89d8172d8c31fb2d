""".stx1 files written by the protobuf library itself (schema compiled from
tests/stixel/proto with protoc), with every field dumped for comparison: the C++
tests decode them with our reader and re-encode them byte for byte."""
import sys

import stixel_refutil as ru

np = ru.import_numpy()


def full_world(pb):
    w = pb.StixelWorld()
    s = w.stixel.add()
    s.u, s.vT, s.vB, s.label, s.width, s.idx, s.cluster = 864, 754, 845, 7, 8, 3, -1
    s.d = np.float32(23.681772)
    s.confidence = np.float32(0.75)
    w.stixel.add()  # all defaults: an empty message
    s = w.stixel.add()
    s.confidence = -0.0  # proto3 writes -0.0 (only +0.0 is the default)
    s.d = float("nan")
    s.label = 22
    s.vT = -2147483648
    s.vB = 2147483647
    w.image = b"\x89PNG\r\n\x1a\n" + bytes(range(256)) * 3
    c = w.context
    c.name = "Stra\u00dfe_\U0001F697_0004"
    c.clusters = 5
    cal = c.calibration
    cal.K.extend([2056.282369, 0.0, 939.57798, 0.0, 2056.282369, 641.10308, 0.0, 0.0, 1.0])
    cal.T.extend(list(np.eye(4).reshape(-1)))
    cal.R.extend([1.0] + [0.0] * 15)
    cal.D.extend([0.0449, -0.354, 0.0, 1e-30, -1e30])
    cal.DistortionModel = 1
    cal.reference = "Vehicle2Camera"
    cal.img_name = "frame_0004.png"
    cal.width, cal.height, cal.channels = 1920, 1280, 3
    return w


def frame_world(pb, rng):
    w = pb.StixelWorld()
    n = 15360
    u = np.repeat(np.arange(240) * 8, 64)
    vT = rng.integers(1, 1281, n)
    vB = rng.integers(1, 1281, n)
    d = rng.uniform(4, 66, n).astype(np.float32)
    p = rng.random(n, dtype=np.float32)
    cl = rng.integers(-1, 50, n)
    for i in range(n):
        s = w.stixel.add()
        s.u, s.vT, s.vB, s.width, s.cluster = int(u[i]), int(vT[i]), int(vB[i]), 8, int(cl[i])
        s.d = d[i]
        s.confidence = p[i]
    w.context.name = "frame"
    w.context.clusters = 49
    w.context.calibration.K.extend([2000.0, 0.0, 960.0, 0.0, 2000.0, 640.0, 0.0, 0.0, 1.0])
    w.context.calibration.T.extend(list(np.eye(4).reshape(-1)))
    w.context.calibration.width = 1920
    w.context.calibration.height = 1280
    return w


# Unknown fields as another writer (a newer schema) could add them: at the top
# level (varint 15, length-delimited 16, fixed64 17, fixed32 18, group 19 with a
# varint inside) and inside one more stixel (u = 5 and varint field 20).
UNKNOWN = bytes([0x78, 0x2a, 0x82, 0x01, 0x03]) + b"xyz" + bytes([0x89, 0x01]) + bytes(8) + \
    bytes([0x95, 0x01, 1, 2, 3, 4, 0x9b, 0x01, 0x08, 0x01, 0x9c, 0x01]) + \
    bytes([0x0a, 0x05, 0x08, 0x05, 0xa0, 0x01, 0x07])


def main(argv):
    a = ru.args(argv)
    pb = ru.protobuf_module(a.out)
    rng = np.random.default_rng(31)
    full = full_world(pb).SerializeToString()
    empty_ctx = pb.StixelWorld()
    empty_ctx.context.clusters = -1
    empty_ctx.context.calibration.SetInParent()
    files = {
        "full": full,
        "unknown": full + UNKNOWN,
        "empty": b"",
        "negative": empty_ctx.SerializeToString(),
        "frame": frame_world(pb, rng).SerializeToString(),
    }
    for name, data in files.items():
        msg = pb.StixelWorld()
        msg.ParseFromString(data)
        with open("%s/stixel_proto_%s.stx1" % (a.out, name), "wb") as f:
            f.write(data)
        tensors, meta = ru.dump_world(np, msg)
        ru.save("%s/stixel_proto_%s.safetensors" % (a.out, name), tensors, meta)
    print("protobuf-written .stx1 references:", ", ".join(files))


if __name__ == "__main__":
    main(sys.argv[1:])
