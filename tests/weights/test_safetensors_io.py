#!/usr/bin/python3
"""Tests for weights/safetensors_io.py: round trips of every dtype, alignment,
little-endian storage, atomic writes and rejection of malformed files.

Usage: test_safetensors_io.py BUILD_DIR
"""

import json
import os
import shutil
import struct
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
WEIGHTS = os.path.normpath(os.path.join(HERE, "..", "..", "weights"))
HINT = "install python3-torch (apt-get install python3-torch)"

failures = []


def check(cond, what):
    if not cond:
        failures.append(what)
        print(f"FAIL: {what}", file=sys.stderr)


def expect_error(fn, fragment, what):
    try:
        fn()
    except Exception as e:  # noqa: BLE001 - any exception type is acceptable, the text matters
        check(fragment in str(e), f"{what}: message {str(e)!r} lacks {fragment!r}")
        return
    check(False, f"{what}: no error raised")


def raw_file(path, header, data=b"", claimed=None):
    text = header.encode("utf-8") if isinstance(header, str) else header
    with open(path, "wb") as f:
        f.write(struct.pack("<Q", len(text) if claimed is None else claimed) + text + data)


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    try:
        import numpy as np
        import torch
    except ImportError as e:
        print(f"test_safetensors_io.py: {HINT} ({e})", file=sys.stderr)
        return 1
    sys.path.insert(0, WEIGHTS)
    import safetensors_io as sio

    work = os.path.join(sys.argv[1], "weights_safetensors_io_test")
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    path = os.path.join(work, "t.safetensors")

    # Importing the module must not pull in torch.
    probe = subprocess.run([sys.executable, "-c", "import sys; sys.path.insert(0, sys.argv[1]); "
                            "import safetensors_io; print('torch' in sys.modules)", WEIGHTS],
                           capture_output=True, text=True)
    check(probe.returncode == 0 and probe.stdout.strip() == "False", "import pulls in torch")

    # Round trip of every numpy dtype, including 0-d, empty and big-endian input.
    rng = np.random.default_rng(0)
    tensors = {
        "f64": rng.standard_normal((3, 2)),
        "f32": rng.standard_normal((2, 3, 4)).astype(np.float32),
        "f16": rng.standard_normal(7).astype(np.float16),
        "i64": np.array([-(2**63), 2**63 - 1, 0], dtype=np.int64),
        "i32": np.array([[-1, 2]], dtype=np.int32),
        "i16": np.array([-32768, 32767], dtype=np.int16),
        "i8": np.array([-128, 127], dtype=np.int8),
        "u8": np.arange(256, dtype=np.uint8),
        "bool": np.array([True, False, True]),
        "scalar": np.float32(2.5),
        "empty": np.zeros((0, 3), dtype=np.float32),
        "be": np.arange(6, dtype=">i4").reshape(2, 3),
        "strided": np.arange(20, dtype=np.float32).reshape(4, 5)[:, ::2],
    }
    sio.save(path, tensors, {"k": "v", "unicode": "\u00e9\u20ac"})
    with open(path, "rb") as f:
        blob = f.read()
    (n,) = struct.unpack("<Q", blob[:8])
    check((8 + n) % 64 == 0, "data section not 64-byte aligned")
    header = json.loads(blob[8:8 + n])
    check(header["be"]["dtype"] == "I32", "big-endian int32 not stored as I32")
    check(header["bool"]["dtype"] == "BOOL", "bool dtype")
    check(list(header)[1:] == list(tensors), "header order differs from insertion order")
    loaded, meta = sio.load(path)
    check(meta == {"k": "v", "unicode": "\u00e9\u20ac"}, f"metadata {meta}")
    check(list(loaded) == list(tensors), f"names/order {list(loaded)}")
    for name, want in tensors.items():
        got = loaded[name]
        want = np.asarray(want)
        check(got.shape == want.shape, f"{name}: shape {got.shape} != {want.shape}")
        check(got.dtype == want.dtype.newbyteorder("="), f"{name}: dtype {got.dtype}")
        check(np.array_equal(got, want), f"{name}: values differ")
        check(got.flags.writeable, f"{name}: loaded array is read-only")
    data_start = 8 + n
    be_begin = header["be"]["data_offsets"][0]
    check(blob[data_start + be_begin:data_start + be_begin + 8] == b"\0\0\0\0\1\0\0\0",
          "big-endian input not stored little-endian")

    # torch tensors, including bfloat16 (widened to float32 on load).
    t = {"w": torch.linspace(-2, 2, 9).reshape(3, 3), "bf": torch.tensor([1.0, 0.1, -3e38]).bfloat16(),
         "grad": torch.ones(2, requires_grad=True), "h": torch.tensor([0.5]).half()}
    sio.save(path, t)
    loaded, meta = sio.load(path)
    check(meta == {}, "metadata should be empty")
    check(np.array_equal(loaded["w"], t["w"].numpy()), "torch f32 values")
    check(loaded["bf"].dtype == np.float32 and np.array_equal(loaded["bf"], t["bf"].float().numpy()),
          "bf16 widening")
    check(loaded["h"].dtype == np.float16 and loaded["h"][0] == 0.5, "torch f16")
    check(np.array_equal(loaded["grad"], np.ones(2, np.float32)), "requires_grad tensor")

    # Bad input to save.
    expect_error(lambda: sio.save(path, {"__metadata__": np.zeros(1)}), "reserved", "reserved name")
    expect_error(lambda: sio.save(path, {"__pad__x": np.zeros(1)}), "reserved", "padding name")
    expect_error(lambda: sio.save(path, {"": np.zeros(1)}), "non-empty", "empty name")
    expect_error(lambda: sio.save(path, {"c": np.zeros(1, np.complex64)}), "unsupported dtype", "complex")
    expect_error(lambda: sio.save(path, {"u": np.zeros(1, np.uint32)}), "unsupported dtype", "uint32")
    expect_error(lambda: sio.save(path, {"r": np.zeros([1] * 9)}), "rank 9", "rank 9")
    expect_error(lambda: sio.save(path, {"x": np.zeros(1)}, {"k": 1}), "str to str", "metadata value")

    # Atomic writes: nothing left behind on failure, old file intact.
    before = sorted(os.listdir(work))
    expect_error(lambda: sio.save(os.path.join(work, "missing", "x.safetensors"), {"a": np.zeros(1)}),
                 "No such file", "missing directory")
    check(sorted(os.listdir(work)) == before, "files left behind after a failed save")
    sio.save(path, {"a": np.ones(2, np.float32)})
    expect_error(lambda: sio.save(path, {"a": np.ones(1), "bad": np.zeros(1, np.complex64)}),
                 "unsupported", "failing save")
    check(np.array_equal(sio.load(path)[0]["a"], np.ones(2, np.float32)), "failed save clobbered file")
    check(sorted(os.listdir(work)) == before, "temporary files left behind")

    # Malformed files.
    e = '"a":{"dtype":"F32","shape":[2],"data_offsets":[0,8]}'
    bad = os.path.join(work, "bad.safetensors")
    cases = [
        (lambda: open(bad, "wb").write(b"\1\0"), "too short"),
        (lambda: raw_file(bad, "{}", claimed=999), "runs past the end"),
        (lambda: raw_file(bad, "{}", claimed=2**40), "exceeds the limit"),
        (lambda: raw_file(bad, "{" + e + "," + e + "}", bytes(8)), "duplicate key"),
        (lambda: raw_file(bad, "{" + e + "}", bytes(10)), "2 trailing bytes"),
        (lambda: raw_file(bad, "{" + e + "}", bytes(4)), "truncated"),
        (lambda: raw_file(bad, '{"a":{"dtype":"X9","shape":[2],"data_offsets":[0,8]}}', bytes(8)),
         "unknown dtype"),
        (lambda: raw_file(bad, '{"a":{"dtype":"F32","shape":[2.0],"data_offsets":[0,8]}}', bytes(8)),
         "bad shape"),
        (lambda: raw_file(bad, '{"a":{"dtype":"F32","shape":[true],"data_offsets":[0,4]}}', bytes(4)),
         "bad shape"),
        (lambda: raw_file(bad, '{"a":{"dtype":"F32","shape":[3],"data_offsets":[0,8]}}', bytes(8)),
         "needs 12"),
        (lambda: raw_file(bad, '{"a":{"dtype":"F32","shape":[1],"data_offsets":[0,4]},'
                               '"b":{"dtype":"F32","shape":[1],"data_offsets":[8,12]}}', bytes(12)), "gap"),
        (lambda: raw_file(bad, '{"a":{"dtype":"F32","shape":[2],"data_offsets":[0,8]},'
                               '"b":{"dtype":"F32","shape":[1],"data_offsets":[4,8]}}', bytes(8)), "overlap"),
        (lambda: raw_file(bad, '{"__metadata__":{"k":1}}'), "__metadata__"),
        (lambda: raw_file(bad, '{"a":NaN}'), "NaN"),
        (lambda: raw_file(bad, b'{"\xff":1}'), "header"),
    ]
    for make, fragment in cases:
        make()
        expect_error(lambda: sio.load(bad), fragment, f"malformed file ({fragment})")

    if failures:
        print(f"test_safetensors_io.py: {len(failures)} failure(s)", file=sys.stderr)
        return 1
    print("test_safetensors_io.py: all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
