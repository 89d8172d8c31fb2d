#!/usr/bin/python3
"""Convert a PyTorch checkpoint into a safetensors file for roadnn.

StixelNExT++ files describe themselves: --preset waymo|coopscenes and --meta
stixelnext.KEY=VALUE write the settings stixelnext and the C API read from
__metadata__ (stixel/predictor.h, stixel/model_file.h). A .safetensors file is
accepted as CHECKPOINT too, to add or change metadata of an exported file.

Runs with /usr/bin/python3 using torch and the standard library only (no
`safetensors` package). Accepted checkpoint forms: a bare state_dict,
{"model_state_dict": ...}, {"state_dict": ...}, {"model": ...} and a pickled
nn.Module. A detectron2 checkpoint is {"model": ...} too: the trainer's
model_final.pth ({"model", "trainer", "iteration"}, torch.save'd) and the model
zoo's model_final_*.pkl (a plain pickle whose values are numpy arrays) both load.
A DataParallel/DDP "module." prefix is stripped, BatchNorm
num_batches_tracked counters are dropped, other non-float tensors are skipped
with a warning, and float tensors are stored contiguous in the chosen dtype.
"""

import argparse
import os
import sys

PROG = "export.py"
TORCH_HINT = "install python3-torch (apt-get install python3-torch)"
FORMAT = "roadnn-v1"
RESERVED_METADATA = ("format", "source")
# The published StixelNExT++ setups; stixel/model_file.cpp has the same table
# (stixelnext_cli_tests compares the two).
PRESETS = {
    "waymo": {"stixelnext.input_height": "1280", "stixelnext.input_width": "1920",
              "stixelnext.columns": "240", "stixelnext.stixel_width": "8",
              "stixelnext.normalization": "raw255", "stixelnext.anchors": "tangent:4,66,64"},
    "coopscenes": {"stixelnext.input_height": "1200", "stixelnext.input_width": "1920",
                   "stixelnext.columns": "120", "stixelnext.stixel_width": "16",
                   "stixelnext.normalization": "imagenet", "stixelnext.anchors": "tangent:4,66,64"},
}
STIXEL_KEYS = {
    "stixelnext.head": ("v0", "v1", "v2", "v3", "v4"),
    "stixelnext.normalization": ("raw255", "unit", "imagenet"),
    "stixelnext.input_height": None, "stixelnext.input_width": None,
    "stixelnext.columns": None, "stixelnext.stixel_width": None,
    "stixelnext.anchors": None,
}
WRAPPER_KEYS = ("model_state_dict", "state_dict", "model")


class ExportError(Exception):
    """A problem to report as one line, exit code 1."""


def parse_args(argv):
    parser = argparse.ArgumentParser(
        prog=PROG,
        description="Convert a PyTorch checkpoint (bare state_dict, {'model_state_dict': ...}, "
        "{'state_dict': ...}, {'model': ...} or a pickled nn.Module) into safetensors for roadnn. "
        "detectron2's model_final.pth ({'model', 'trainer', 'iteration'}) and model zoo .pkl files "
        "(plain pickles of numpy arrays) are {'model': ...} checkpoints.",
        epilog="Security: checkpoints are Python pickles and are loaded with "
        "torch.load(weights_only=False) (or pickle.load for plain pickles), which can run arbitrary "
        "code. Only convert checkpoints "
        "you trust. Output metadata always has format=%s and source=<checkpoint file name>."
        % FORMAT,
    )
    parser.add_argument("checkpoint", metavar="CHECKPOINT", help="PyTorch checkpoint (.pt/.pth), or a .safetensors file to re-export with new metadata")
    parser.add_argument("out", metavar="OUT.safetensors", help="output file (written atomically)")
    parser.add_argument("--meta", "--metadata", dest="metadata", metavar="KEY=VALUE", nargs="+",
                        action="extend", default=[],
                        help="extra __metadata__ entries (repeatable), e.g. stixelnext.head=v3; "
                        "stixelnext.* keys: head (v0..v4), normalization (raw255, unit, imagenet), "
                        "input_height, input_width, columns, stixel_width, anchors (tangent:4,66,64, "
                        "linear:START,END,N); they override --preset")
    parser.add_argument("--preset", choices=sorted(PRESETS),
                        help="StixelNExT++ settings of a published setup: waymo (1280x1920, 240 columns of "
                        "8 px, raw 0..255) or coopscenes (1200x1920, 120 columns of 16 px, ImageNet mean/std)")
    parser.add_argument("--dtype", choices=("f32", "f16", "bf16"), default="f32",
                        help="storage type of the float tensors (default: f32)")
    return parser.parse_args(argv)


def parse_metadata(items):
    metadata = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise ExportError(f"--metadata expects KEY=VALUE, got '{item}'")
        if key in RESERVED_METADATA:
            raise ExportError(f"--metadata key '{key}' is reserved (set automatically)")
        if key in metadata:
            raise ExportError(f"--metadata key '{key}' given twice")
        if key.startswith("stixelnext."):
            check_stixel_key(key, value)
        metadata[key] = value
    return metadata


def check_stixel_key(key, value):
    """A typo in a stixelnext.* key or value would only show when the file runs."""
    if key not in STIXEL_KEYS:
        raise ExportError(f"--meta key '{key}' is not a stixelnext setting (known: "
                          + ", ".join(sorted(STIXEL_KEYS)) + ")")
    allowed = STIXEL_KEYS[key]
    if allowed is not None and value not in allowed:
        raise ExportError(f"--meta {key}={value!r}: expected one of " + ", ".join(allowed))
    if key.endswith(("_height", "_width", "columns")) and not (value.isdigit() and int(value) > 0):
        raise ExportError(f"--meta {key}={value!r}: expected a positive integer")
    if key == "stixelnext.anchors" and not (value == "tangent" or value.startswith(("tangent:", "linear:"))):
        raise ExportError(f"--meta {key}={value!r}: expected tangent, tangent:START,END,N or linear:START,END,N")


def ambiguous_head(tensors, metadata):
    """V1 and V3 heads have the same tensors: say so when nothing names the head."""
    reduce = tensors.get("classifier.channel_reduce.weight")
    query = tensors.get("classifier.attention_layer.query_layer.weight")
    return ("stixelnext.head" not in metadata and reduce is not None and query is not None
            and reduce.dim() == 4 and reduce.shape[1] == 2 * query.shape[1])


def first_line(exc):
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0]}" if text else type(exc).__name__


def load_plain_pickle(path):
    """detectron2's model zoo .pkl files: a plain pickle (latin1 for Caffe2-era ones)."""
    import pickle

    with open(path, "rb") as f:
        return pickle.load(f, encoding="latin1")


def load_checkpoint(torch, path):
    if not os.path.exists(path):
        raise ExportError(f"{path}: no such file")
    if os.path.isdir(path):
        raise ExportError(f"{path}: is a directory, expected a checkpoint file")
    try:
        try:
            return torch.load(path, map_location="cpu", weights_only=False)
        except TypeError as e:
            if "weights_only" not in str(e):
                raise
            return torch.load(path, map_location="cpu")  # torch < 1.13
    except Exception as e:  # torch/pickle raise many unrelated types for bad files
        # torch.load reads a plain pickle's first object as its magic number.
        if "magic number" in str(e):
            try:
                return load_plain_pickle(path)
            except Exception:
                pass
        hint = ""
        if isinstance(e, AttributeError) and "Can't get attribute" in str(e):
            hint = "; a pickled nn.Module needs its class importable, save its state_dict() instead"
        raise ExportError(f"{path}: cannot load checkpoint ({first_line(e)}){hint}") from e


def is_array(torch, v):
    """A tensor, or a numpy array (detectron2's pickled checkpoints)."""
    return isinstance(v, torch.Tensor) or type(v).__module__ == "numpy" and type(v).__name__ == "ndarray"


def is_state_dict(torch, obj):
    from collections.abc import Mapping

    return isinstance(obj, Mapping) and len(obj) > 0 and all(is_array(torch, v) for v in obj.values())


def find_state_dict(torch, obj, path):
    """The name -> tensor mapping inside a checkpoint, and a word on its form."""
    from collections.abc import Mapping

    if isinstance(obj, torch.nn.Module):
        return obj.state_dict(), "pickled nn.Module"
    if isinstance(obj, Mapping):
        for key in WRAPPER_KEYS:
            inner = obj.get(key)
            if isinstance(inner, torch.nn.Module):
                return inner.state_dict(), f"pickled nn.Module under '{key}'"
            if is_state_dict(torch, inner):
                return inner, f"'{key}'"
        if is_state_dict(torch, obj):
            return obj, "bare state_dict"
        if not obj:
            raise ExportError(f"{path}: the checkpoint is an empty dict")
        keys = ", ".join(repr(k) for k in list(obj)[:10]) + (", ..." if len(obj) > 10 else "")
        raise ExportError(f"{path}: no state dict found (expected a state_dict, "
                          f"{{'model_state_dict': ...}}, {{'state_dict': ...}} or a pickled nn.Module; "
                          f"top-level keys: {keys})")
    raise ExportError(f"{path}: unsupported checkpoint content: {type(obj).__name__} "
                      "(expected a state_dict or a pickled nn.Module)")


def select_tensors(torch, state, dtype, path):
    """Float tensors converted to `dtype`; returns (tensors, skipped descriptions)."""
    names = list(state.keys())
    for name in names:
        if not isinstance(name, str):
            raise ExportError(f"{path}: state dict key {name!r} is not a string")
    # DataParallel/DDP prefix every key; strip only then, so a submodule that
    # happens to be called "module" keeps its name.
    strip = all(n.startswith("module.") for n in names)
    tensors = {}
    skipped = []
    for name in names:
        value = state[name]
        if is_array(torch, value) and not isinstance(value, torch.Tensor):
            try:
                value = torch.as_tensor(value)
            except Exception as e:
                raise ExportError(f"{path}: array '{name}': cannot convert ({first_line(e)})") from e
        out_name = name[len("module."):] if strip else name
        if out_name == "num_batches_tracked" or out_name.endswith(".num_batches_tracked"):
            continue
        if not isinstance(value, torch.Tensor):
            skipped.append(f"{out_name} ({type(value).__name__})")
            continue
        if not value.is_floating_point():
            skipped.append(f"{out_name} ({str(value.dtype).replace('torch.', '')})")
            continue
        try:
            converted = value.detach().to(device="cpu", dtype=dtype).contiguous()
        except Exception as e:
            raise ExportError(f"{path}: tensor '{out_name}': cannot convert ({first_line(e)})") from e
        if not bool(torch.isfinite(converted).all()):
            if bool(torch.isfinite(value).all()):
                raise ExportError(f"{path}: tensor '{out_name}' has values outside the range of "
                                  f"{str(dtype).replace('torch.', '')}")
            raise ExportError(f"{path}: tensor '{out_name}' contains NaN or Inf")
        if out_name in tensors:
            raise ExportError(f"{path}: two tensors named '{out_name}' after stripping 'module.'")
        tensors[out_name] = converted
    return tensors, skipped


def load_safetensors(path):
    """An exported file as input: its tensors (as torch) and its metadata."""
    import safetensors_io
    import torch
    try:
        arrays, metadata = safetensors_io.load(path)
    except OSError as e:
        raise ExportError(f"{path}: cannot read ({e.strerror or first_line(e)})") from e
    except safetensors_io.SafetensorsError as e:
        raise ExportError(str(e)) from e
    return {k: torch.from_numpy(v.copy()) for k, v in arrays.items()}, metadata


def export(args):
    metadata = dict(PRESETS[args.preset]) if args.preset else {}
    metadata.update(parse_metadata(args.metadata))
    try:
        import torch
    except ImportError as e:
        raise ExportError(TORCH_HINT) from e
    here = os.path.dirname(os.path.abspath(__file__))
    if here not in sys.path:
        sys.path.insert(0, here)
    import safetensors_io

    dtype = {"f32": torch.float32, "f16": torch.float16, "bf16": torch.bfloat16}[args.dtype]
    if args.checkpoint.endswith(".safetensors"):
        state, old = load_safetensors(args.checkpoint)
        form = "safetensors (metadata kept, new keys over it)"
        metadata = {**{k: v for k, v in old.items() if k not in RESERVED_METADATA}, **metadata}
    else:
        obj = load_checkpoint(torch, args.checkpoint)
        state, form = find_state_dict(torch, obj, args.checkpoint)
    tensors, skipped = select_tensors(torch, state, dtype, args.checkpoint)
    if skipped:
        print(f"{PROG}: warning: skipped {len(skipped)} non-float tensor(s): " + ", ".join(skipped),
              file=sys.stderr)
    if not tensors:
        raise ExportError(f"{args.checkpoint}: no float tensors to export")
    if ambiguous_head(tensors, metadata):
        print(f"{PROG}: warning: the stixel head's tensors fit both V1 (attention over neighbouring columns) "
              "and V3 (over all columns); add --meta stixelnext.head=v1 or v3 so that runs know which",
              file=sys.stderr)
    metadata.update({"format": FORMAT, "source": os.path.basename(args.checkpoint)})
    try:
        safetensors_io.save(args.out, tensors, metadata)
    except OSError as e:
        raise ExportError(f"{args.out}: cannot write ({e.strerror or first_line(e)})") from e
    except safetensors_io.SafetensorsError as e:
        raise ExportError(f"{args.out}: {e}") from e
    nbytes = sum(t.numel() * t.element_size() for t in tensors.values())
    print(f"wrote {args.out}: {len(tensors)} tensors ({args.dtype}, {nbytes} bytes) from {form}")


def main(argv=None):
    args = parse_args(argv)
    try:
        export(args)
    except ExportError as e:
        print(f"{PROG}: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
