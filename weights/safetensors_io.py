"""Read and write safetensors files with the standard library and numpy.

The files match what the C++ reader (weights/safetensors.h) accepts: a
little-endian u64 header length, a JSON header padded with spaces so the data
starts 64-byte aligned, then the tensors back to back in the order given.

    save(path, {"w": array_or_tensor, ...}, metadata={"k": "v"})
    tensors, metadata = load(path)

torch is optional and imported only when a torch.Tensor is saved (needed for
bfloat16, which numpy lacks). load() returns BF16 tensors widened to float32.
Importing this module has no side effects.
"""

import json
import os
import struct

import numpy as np

__all__ = ["save", "load", "SafetensorsError", "MAX_HEADER_BYTES", "ALIGNMENT"]

MAX_HEADER_BYTES = 100_000_000
ALIGNMENT = 64
MAX_RANK = 8
PADDING_PREFIX = "__pad__"

# (numpy kind, item size) -> safetensors dtype; byte order is handled separately.
_KIND_TO_DTYPE = {
    ("f", 8): "F64",
    ("f", 4): "F32",
    ("f", 2): "F16",
    ("i", 8): "I64",
    ("i", 4): "I32",
    ("i", 2): "I16",
    ("i", 1): "I8",
    ("u", 1): "U8",
    ("b", 1): "BOOL",
}

_DTYPE_TO_NUMPY = {
    "F64": np.dtype("<f8"),
    "F32": np.dtype("<f4"),
    "F16": np.dtype("<f2"),
    "BF16": np.dtype("<u2"),  # raw bits, widened on load
    "I64": np.dtype("<i8"),
    "I32": np.dtype("<i4"),
    "I16": np.dtype("<i2"),
    "I8": np.dtype("i1"),
    "U8": np.dtype("u1"),
    "BOOL": np.dtype("?"),
}


class SafetensorsError(ValueError):
    """A malformed file or an unsupported tensor; the message names the file."""


def _is_torch_tensor(value):
    cls = type(value)
    return cls.__module__.split(".")[0] == "torch" and hasattr(value, "detach")


def _tensor_bytes(name, value):
    """(dtype, shape, little-endian bytes) of a numpy array or torch tensor."""
    if _is_torch_tensor(value):
        import torch  # only when the caller already uses torch

        t = value.detach().cpu().contiguous()
        if t.dtype == torch.bfloat16:
            bits = t.view(torch.int16).numpy().astype("<i2", copy=False)
            return "BF16", list(t.shape), bits.tobytes()
        arr = t.numpy()
    else:
        arr = np.asarray(value)
    dtype = _KIND_TO_DTYPE.get((arr.dtype.kind, arr.dtype.itemsize))
    if dtype is None:
        raise SafetensorsError(f"tensor '{name}': unsupported dtype {arr.dtype}")
    little = np.ascontiguousarray(arr, dtype=arr.dtype.newbyteorder("<"))
    # A byte view, not a copy: saving a multi-GB dump (scripts/torch_dump.py) must not
    # need twice its size in memory.
    return dtype, list(arr.shape), memoryview(little.reshape(-1)).cast("B")


def _check_name(name):
    if not isinstance(name, str) or not name:
        raise SafetensorsError(f"tensor names must be non-empty strings, got {name!r}")
    if name == "__metadata__" or name.startswith(PADDING_PREFIX):
        raise SafetensorsError(f"tensor name '{name}' is reserved")
    try:
        name.encode("utf-8")
    except UnicodeEncodeError as e:
        raise SafetensorsError(f"tensor name {name!r} is not valid UTF-8") from e


def _write_atomically(path, pieces):
    """Write to a new file beside `path`, then rename: never a partial file."""
    directory = os.path.dirname(os.path.abspath(path))
    base = os.path.basename(path)
    for attempt in range(100):
        tmp = os.path.join(directory, f".{base}.tmp-{os.getpid()}-{attempt}")
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
            break
        except FileExistsError:
            continue
    else:
        raise OSError(f"{path}: cannot create a temporary file next to it")
    try:
        with os.fdopen(fd, "wb") as f:
            for piece in pieces:
                f.write(piece)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def save(path, tensors, metadata=None):
    """Write `tensors` (name -> numpy array or torch tensor, in order) to `path`.

    metadata: optional str -> str dict stored as __metadata__.
    Raises SafetensorsError for unsupported input, OSError for I/O failures.
    """
    header = {}
    if metadata:
        for k, v in metadata.items():
            if not isinstance(k, str) or not isinstance(v, str):
                raise SafetensorsError(f"metadata must map str to str, got {k!r}: {v!r}")
        header["__metadata__"] = dict(metadata)
    blobs = []
    offset = 0
    for name, value in tensors.items():
        _check_name(name)
        dtype, shape, blob = _tensor_bytes(name, value)
        if len(shape) > MAX_RANK:
            raise SafetensorsError(f"tensor '{name}': rank {len(shape)} exceeds {MAX_RANK}")
        header[name] = {"dtype": dtype, "shape": shape, "data_offsets": [offset, offset + len(blob)]}
        blobs.append(blob)
        offset += len(blob)
    text = json.dumps(header, separators=(",", ":"), ensure_ascii=False).encode("utf-8")
    text += b" " * (-(8 + len(text)) % ALIGNMENT)
    _write_atomically(path, [struct.pack("<Q", len(text)), text] + blobs)


def _reject_duplicates(pairs):
    keys = set()
    for k, _ in pairs:
        if k in keys:
            raise ValueError(f"duplicate key {k!r}")
        keys.add(k)
    return dict(pairs)


def _reject_constant(token):
    raise ValueError(f"{token} is not valid JSON")


def _non_negative_int(x):
    return isinstance(x, int) and not isinstance(x, bool) and x >= 0


def load(path):
    """Read `path`; returns (dict name -> numpy array in file order, metadata dict).

    Validates like the C++ reader; raises SafetensorsError naming the file.
    BF16 tensors come back as float32 (exactly widened).
    """
    with open(path, "rb") as f:
        data = f.read()

    def fail(problem):
        raise SafetensorsError(f"{path}: {problem}")

    if len(data) < 8:
        fail(f"file is {len(data)} bytes, too short for the 8-byte header length")
    (n,) = struct.unpack("<Q", data[:8])
    if n > MAX_HEADER_BYTES:
        fail(f"header length {n} exceeds the limit of {MAX_HEADER_BYTES} bytes")
    if 8 + n > len(data):
        fail(f"header length {n} runs past the end of the file (size {len(data)})")
    try:
        header = json.loads(data[8 : 8 + n].decode("utf-8"), object_pairs_hook=_reject_duplicates,
                            parse_constant=_reject_constant)
    except (UnicodeDecodeError, ValueError) as e:
        fail(f"header: {e}")
    if not isinstance(header, dict):
        fail("header is not a JSON object")

    metadata = header.pop("__metadata__", {})
    if not isinstance(metadata, dict) or not all(isinstance(v, str) for v in metadata.values()):
        fail("__metadata__ must be an object of strings")

    data_start = 8 + n
    data_size = len(data) - data_start
    entries = []
    for name, e in header.items():
        if not isinstance(e, dict) or set(e) != {"dtype", "shape", "data_offsets"}:
            fail(f"tensor '{name}': entry must have exactly dtype, shape, data_offsets")
        dtype, shape, offsets = e["dtype"], e["shape"], e["data_offsets"]
        if dtype not in _DTYPE_TO_NUMPY:
            fail(f"tensor '{name}': unknown dtype {dtype!r}")
        if not isinstance(shape, list) or len(shape) > MAX_RANK or not all(map(_non_negative_int, shape)):
            fail(f"tensor '{name}': bad shape {shape!r}")
        if not isinstance(offsets, list) or len(offsets) != 2 or not all(map(_non_negative_int, offsets)):
            fail(f"tensor '{name}': bad data_offsets {offsets!r}")
        numel = 1
        for d in shape:
            numel *= d
        nbytes = numel * _DTYPE_TO_NUMPY[dtype].itemsize
        begin, end = offsets
        if end - begin != nbytes:
            fail(f"tensor '{name}': data_offsets {offsets} hold {end - begin} bytes, shape {shape} "
                 f"of {dtype} needs {nbytes}")
        entries.append((begin, end, len(entries), name, dtype, shape))

    entries.sort()
    pos = 0
    previous = None
    for begin, end, _, name, _, _ in entries:
        if begin > pos:
            fail(f"gap of {begin - pos} bytes before tensor '{name}'")
        if begin < pos:
            fail(f"overlap: tensor '{name}' overlaps tensor '{previous}'")
        pos = end
        previous = name
    if pos > data_size:
        fail(f"data truncated: tensors need {pos} data bytes, the file has {data_size}")
    if pos < data_size:
        fail(f"{data_size - pos} trailing bytes after the last tensor")

    tensors = {}
    for begin, end, _, name, dtype, shape in entries:
        if name.startswith(PADDING_PREFIX):
            continue
        raw = np.frombuffer(data, dtype=_DTYPE_TO_NUMPY[dtype], count=(end - begin) //
                            _DTYPE_TO_NUMPY[dtype].itemsize, offset=data_start + begin)
        if dtype == "BF16":
            arr = (raw.astype(np.uint32) << 16).view(np.float32)
        else:
            arr = raw.astype(raw.dtype.newbyteorder("="))  # a writable native-order copy
        tensors[name] = arr.reshape(shape)
    return tensors, dict(metadata)
