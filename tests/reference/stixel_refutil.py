"""Shared helpers of the stixel reference scripts: output folder, safetensors
output through weights/safetensors_io.py, and the protobuf module compiled from
tests/stixel/proto with protoc (python3-protobuf + protobuf-compiler)."""
import argparse
import importlib
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
PROTO_DIR = os.path.join(ROOT, "tests", "stixel", "proto")
sys.path.insert(0, os.path.join(ROOT, "weights"))

PROTOBUF_HINT = ("the .stx1 compatibility tests need protoc and the protobuf Python module for "
                 "/usr/bin/python3: apt-get install -y protobuf-compiler python3-protobuf")
NUMPY_HINT = "the stixel reference scripts need numpy: apt-get install -y python3-numpy"


def import_numpy():
    try:
        import numpy  # noqa: F401
    except ImportError as e:
        sys.exit("error: %s (%s)" % (NUMPY_HINT, e))
    import numpy
    return numpy


def args(argv, extra=(), need_out=True):
    """--out DIR plus the script's own options ((flag, kwargs) pairs)."""
    ap = argparse.ArgumentParser()
    if need_out:
        ap.add_argument("--out", required=True, help="folder for the reference files")
    for flag, kw in extra:
        ap.add_argument(flag, **kw)
    a = ap.parse_args(argv)
    if getattr(a, "out", None):
        os.makedirs(a.out, exist_ok=True)
    return a


def save(path, tensors, metadata=None):
    import safetensors_io
    safetensors_io.save(path, tensors, {k: str(v) for k, v in (metadata or {}).items()})


def protobuf_module(build_dir):
    """Compiles the two .proto files into build_dir/stixel_pb and imports
    stixel_world_pb2 from there (cached between calls in one process)."""
    try:
        import google.protobuf  # noqa: F401
    except ImportError as e:
        sys.exit("error: %s (%s)" % (PROTOBUF_HINT, e))
    protoc = shutil.which("protoc")
    if protoc is None:
        sys.exit("error: protoc not found; " + PROTOBUF_HINT)
    out = os.path.join(build_dir, "stixel_pb")
    os.makedirs(out, exist_ok=True)
    subprocess.run([protoc, "-I", PROTO_DIR, "--python_out", out,
                    os.path.join(PROTO_DIR, "segmentation.proto"),
                    os.path.join(PROTO_DIR, "stixel_world.proto")], check=True)
    return load_protobuf_module(out)


def load_protobuf_module(pb_dir):
    try:
        import google.protobuf  # noqa: F401
    except ImportError as e:
        sys.exit("error: %s (%s)" % (PROTOBUF_HINT, e))
    if pb_dir not in sys.path:
        sys.path.insert(0, pb_dir)
    return importlib.import_module("stixel_world_pb2")


def tangent_anchors(np, start=4.0, end=66.0, n=64):
    """The reference's create_depth_bins: tangent spacing, a = pi / 2.72, float64."""
    lin = np.linspace(0, np.pi / 2.72, n)
    t = np.tan(lin)
    return start + (t - t.min()) / (t.max() - t.min()) * (end - start)


def linear_anchors(np, start, end, n):
    return np.linspace(start, end, n)


def dump_world(np, msg):
    """Every field of a StixelWorld message as safetensors tensors + metadata,
    for the C++ tests to compare field by field; `canonical` is the message
    serialised by protobuf without unknown fields."""
    st = list(msg.stixel)
    ints = {k: np.array([getattr(s, k) for s in st], dtype=np.int32)
            for k in ("u", "vT", "vB", "label", "width", "idx", "cluster")}
    floats = {k: np.array([getattr(s, k) for s in st], dtype=np.float32) for k in ("d", "confidence")}
    cal = msg.context.calibration
    tensors = dict(ints)
    tensors.update(floats)
    for k in ("K", "T", "R", "D"):
        tensors["calibration_" + k] = np.array(list(getattr(cal, k)), dtype=np.float32)
    tensors["image"] = np.frombuffer(bytes(msg.image), dtype=np.uint8).copy()
    clean = type(msg)()
    clean.CopyFrom(msg)
    clean.DiscardUnknownFields()
    tensors["canonical"] = np.frombuffer(clean.SerializeToString(), dtype=np.uint8).copy()
    meta = {
        "stixels": len(st),
        "name": msg.context.name,
        "clusters": msg.context.clusters,
        "has_context": int(msg.HasField("context")),
        "has_calibration": int(msg.context.HasField("calibration")),
        "distortion_model": int(cal.DistortionModel),
        "reference": cal.reference,
        "img_name": cal.img_name,
        "width": cal.width,
        "height": cal.height,
        "channels": cal.channels,
    }
    return tensors, meta
