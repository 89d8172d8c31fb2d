#!/usr/bin/python3
"""Every module output of the PyTorch model, under its named_modules() name, for nncompare.

The PyTorch side of `nnrun --dump` (docs/NUMERICS.md, dump contract): loads a state_dict
into the module roadnn's model corresponds to (weights/torch_models.py), registers a
forward hook on every module, runs the input in eval mode under torch.no_grad() and
writes each output as a tensor of a safetensors file:
  name          a module's output (NCHW, or whatever layout the module returns)
  name[i]       element i of a tuple/list output, name[key] of a dict (recursively);
                an ImageList counts as its .tensors; None and other non-tensors are skipped
  name#k        call k (k >= 1) of a module called more than once per forward
  metadata      dump.order (names in the order produced), dump.source=torch, dump.model
Runs with /usr/bin/python3, torch and torchvision only.
"""

import argparse
import os
import re
import sys

PROG = "torch_dump.py"
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "weights"))
TORCH_HINT = ("needs Debian's python3-torch and python3-torchvision for /usr/bin/python3: "
              "apt-get install -y python3-torch python3-torchvision python3-numpy")
try:
    import safetensors_io  # noqa: E402  (numpy)
except ImportError as e:
    sys.exit(f"{PROG}: {TORCH_HINT} ({e})")
import torch_models  # noqa: E402
MODELS = torch_models.CONVNEXT_BUILDERS + ("convnext", "stixelnext") + torch_models.DETECTOR_BUILDERS
# nnrun --output's tensor names, written with --outputs.
STIXEL_OUTPUT = "prediction"
STIXEL_FEATURES = 768  # ConvNeXt-Tiny's last stage: the head's input channels


class DumpError(Exception):
    """A problem reported as one line, exit code 1."""


def parse_args(argv):
    ap = argparse.ArgumentParser(
        prog=PROG,
        description="Run the PyTorch module that roadnn's --model corresponds to on the tensor 'input' of "
        "X.safetensors and write every module's output (forward hooks on named_modules()) to a "
        "safetensors dump that nncompare compares with `nnrun --dump`.",
        epilog="models: convnext_tiny/_small/_base and convnext (widths and depths from the weights) run "
        "torchvision's ConvNeXt features (names features.*); stixelnext runs the authors' model "
        "(features.* backbone, classifier.* head; head variant from metadata stixelnext.head or the "
        "tensor names, columns from stixelnext.columns or input width / stixelnext.stixel_width); the "
        "fasterrcnn_* models run torchvision's detector with its default eval settings on input "
        "[1,3,H,W] RGB in [0,1], num_classes from roi_heads.box_predictor.cls_score. "
        "Security: a .pth/.pt checkpoint is a Python pickle (torch.load can run code): use only "
        "checkpoints you trust. Example: scripts/torch_dump.py --model convnext_tiny --weights "
        "w.safetensors --input x.safetensors --output torch.dump.safetensors")
    ap.add_argument("--model", required=True, choices=MODELS, metavar="NAME",
                    help="one of: " + ", ".join(MODELS))
    ap.add_argument("--weights", required=True, metavar="W",
                    help="state_dict as .safetensors (weights/export.py) or a .pth/.pt checkpoint "
                    "(state_dict, {'model_state_dict': ...}, {'state_dict': ...}, {'model': ...})")
    ap.add_argument("--input", required=True, metavar="X.safetensors", help="tensor 'input', as nnrun takes it")
    ap.add_argument("--output", required=True, metavar="DUMP.safetensors", help="the dump (written atomically)")
    ap.add_argument("--filter", metavar="REGEX",
                    help="dump only module outputs whose name contains a match (re.search)")
    ap.add_argument("--outputs", action="store_true",
                    help="also write the model's final outputs under nnrun --output's names "
                    "(features; prediction; boxes, scores, labels)")
    ap.add_argument("--threads", type=int, default=0, metavar="N", help="torch threads (default: torch's choice)")
    return ap.parse_args(argv)


def import_torch():
    try:
        import torch
        import torchvision  # noqa: F401
    except ImportError as e:
        raise DumpError(f"{TORCH_HINT} ({e})") from e
    return torch


def first_line(exc):
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0]}" if text else type(exc).__name__


def check_readable(path, what):
    if not os.path.exists(path):
        raise DumpError(f"{path}: no such file ({what})")
    if os.path.isdir(path):
        raise DumpError(f"{path}: is a directory, expected the {what} file")


def load_weights(torch, path):
    """(name -> float32 torch tensor, metadata) from a safetensors file or a checkpoint."""
    check_readable(path, "weights")
    with open(path, "rb") as f:
        head = f.read(16)
    # A safetensors file starts with a u64 header length and '{'; a checkpoint is a zip or pickle.
    if path.endswith(".safetensors") or head[8:9] == b"{":
        try:
            arrays, metadata = safetensors_io.load(path)
        except (safetensors_io.SafetensorsError, OSError) as e:
            raise DumpError(str(e) if str(e).startswith(path) else f"{path}: {e}") from e
        return {k: torch.from_numpy(v).float() if v.dtype.kind == "f" else torch.from_numpy(v)
                for k, v in arrays.items()}, metadata
    import export  # weights/export.py: the same checkpoint forms the exporter accepts
    try:
        obj = export.load_checkpoint(torch, path)
        state, _ = export.find_state_dict(torch, obj, path)
        tensors, _ = export.select_tensors(torch, state, torch.float32, path)
    except export.ExportError as e:
        raise DumpError(str(e)) from e
    return tensors, {}


def load_input(path):
    check_readable(path, "input")
    try:
        arrays, _ = safetensors_io.load(path)
    except (safetensors_io.SafetensorsError, OSError) as e:
        raise DumpError(str(e) if str(e).startswith(path) else f"{path}: {e}") from e
    if "input" not in arrays:
        raise DumpError(f"{path}: no tensor 'input' (has: {', '.join(list(arrays)[:8]) or 'none'})")
    x = arrays["input"]
    if x.ndim != 4 or x.shape[1] != 3 or x.dtype.kind != "f" or min(x.shape) < 1:
        raise DumpError(f"{path}: tensor 'input' must be float [N,3,H,W], got {x.dtype} {list(x.shape)}")
    return x


def conv_stages(state):
    """(widths, depths) of a ConvNeXt features.* state_dict."""
    widths, depths = [], []
    for stage in range(4):
        idx = 1 + 2 * stage
        blocks = sorted({int(m.group(1)) for k in state
                         for m in [re.match(rf"features\.{idx}\.(\d+)\.block\.0\.weight$", k)] if m})
        if not blocks:
            break
        widths.append(int(state[f"features.{idx}.{blocks[0]}.block.0.weight"].shape[0]))
        depths.append(len(blocks))
    if len(widths) < 1:
        raise DumpError("no ConvNeXt blocks (features.1.0.block.0.weight, ...) in the weights")
    return widths, depths


def stixel_variant(state, metadata, path):
    if "stixelnext.head" in metadata:
        v = metadata["stixelnext.head"]
        if v not in torch_models.STIXEL_HEAD_VARIANTS:
            raise DumpError(f"{path}: metadata stixelnext.head='{v}' is not one of v0..v4")
        return v
    if "classifier.local_mixing.depthwise.weight" in state:
        return "v4"
    if "classifier.reduce.weight" in state:
        return "v0"
    w = state.get("classifier.channel_reduce.weight")
    if w is None:
        raise DumpError(f"{path}: no StixelNExT++ head found (classifier.local_mixing.* for v4, "
                        "classifier.channel_reduce.* for v1/v2/v3, classifier.reduce.* for v0)")
    # V1 and V3 have the same tensors (2C inputs): V1 unless the metadata says v3, as nnrun does.
    return "v1" if w.shape[1] == 2 * STIXEL_FEATURES else "v2"


def metadata_int(metadata, key, default, path):
    if key not in metadata:
        return default
    try:
        v = int(metadata[key])
    except ValueError:
        v = 0
    if v < 1:
        raise DumpError(f"{path}: metadata {key}='{metadata[key]}' is not a positive integer")
    return v


def build(torch, args, state, metadata, x):
    """(module to hook, callable running it on x, module names required from the weights)."""
    name = args.model
    if name in torch_models.CONVNEXT_BUILDERS or name == "convnext":
        if name == "convnext":
            model = torch_models.convnext_from_widths(torch, *conv_stages(state))
        else:
            model = torch_models.convnext(torch, name)
        # nnrun's ConvNeXt output is model.features(x): only that part is hooked and run.
        return model, (lambda t: model.features(t)), ("features.",)
    if name == "stixelnext":
        features = torch_models.convnext(torch, "convnext_tiny").features
        columns = metadata_int(metadata, "stixelnext.columns", 0, args.weights)
        if not columns:
            columns = x.shape[3] // metadata_int(metadata, "stixelnext.stixel_width", 8, args.weights)
        head = torch_models.stixel_head(torch, stixel_variant(state, metadata, args.weights), columns)
        model = torch_models.stixelnext(torch, features, head)
        return model, (lambda t: model(t)), ("",)
    key = "roi_heads.box_predictor.cls_score.weight"
    if key not in state:
        raise DumpError(f"{args.weights}: no tensor '{key}' (a torchvision Faster R-CNN state_dict has it)")
    model = torch_models.detector(torch, name, int(state[key].shape[0]))
    if x.shape[0] != 1:
        raise DumpError(f"{args.input}: detectors take one image, 'input' is {list(x.shape)}")
    # As the tests call torchvision: a list of [3,H,W] images, default transform and thresholds.
    return model, (lambda t: model([t[0]])), ("",)


def load_state(torch, model, state, required, path):
    """Copies `state` into `model`; every parameter/buffer under `required` prefixes must be there."""
    own = model.state_dict()
    missing = [k for k in own if k.startswith(required) and k not in state
               and not k.endswith("num_batches_tracked")]
    if missing:
        more = f" and {len(missing) - 5} more" if len(missing) > 5 else ""
        raise DumpError(f"{path}: missing tensor(s) {', '.join(missing[:5])}{more} for this model")
    used = {k: v for k, v in state.items() if k in own and k.startswith(required)}
    for k, v in used.items():
        if tuple(own[k].shape) != tuple(v.shape):
            raise DumpError(f"{path}: tensor '{k}' has shape {list(v.shape)}, the model expects {list(own[k].shape)}")
    unused = [k for k in state if k not in used]
    if unused:
        more = f" and {len(unused) - 5} more" if len(unused) > 5 else ""
        print(f"{PROG}: warning: {path}: {len(unused)} tensor(s) not used by this model: "
              f"{', '.join(unused[:5])}{more}", file=sys.stderr)
    model.load_state_dict(used, strict=False)
    return model.eval()


class Recorder:
    """Forward hooks that keep every module output under the contract's names."""

    def __init__(self, torch, model, keep):
        self.torch = torch
        self.keep = keep
        self.tensors = {}
        self.calls = {}
        self.hooks = [m.register_forward_hook(self.hook(name)) for name, m in model.named_modules() if name]

    def hook(self, name):
        def record(module, inputs, output):
            k = self.calls.get(name, 0)
            self.calls[name] = k + 1
            self.add(name if k == 0 else f"{name}#{k}", output)
        return record

    def add(self, name, value):
        torch = self.torch
        if isinstance(value, torch.Tensor):
            if not self.keep(name):
                return
            t = value.detach()
            if t.is_floating_point():
                t = t.float()
            elif t.dtype == torch.bool:
                t = t.to(torch.uint8)
            else:
                t = t.long()
            # A copy: a later in-place op (ReLU(inplace=True)) must not change what we saw.
            self.tensors[name] = t.contiguous().clone()
        elif isinstance(value, (tuple, list)):
            for i, v in enumerate(value):
                self.add(f"{name}[{i}]", v)
        elif isinstance(value, dict):
            for key, v in value.items():
                self.add(f"{name}[{key}]", v)
        elif type(value).__name__ == "ImageList" and hasattr(value, "tensors"):
            self.add(name, value.tensors)

    def remove(self):
        for h in self.hooks:
            h.remove()


def final_outputs(torch, model_name, y):
    """The model's outputs under nnrun --output's names."""
    if model_name.startswith("convnext"):
        return {"features": y}
    if model_name == "stixelnext":
        return {STIXEL_OUTPUT: y}
    det = y[0]
    return {"boxes": det["boxes"], "scores": det["scores"], "labels": det["labels"]}


def run(args):
    keep = lambda name: True  # noqa: E731
    if args.filter is not None:
        try:
            pattern = re.compile(args.filter)
        except re.error as e:
            raise DumpError(f"--filter '{args.filter}': not a valid regular expression ({e})") from e
        keep = lambda name: pattern.search(name) is not None  # noqa: E731
    check_readable(args.weights, "weights")
    x_np = load_input(args.input)
    out_dir = os.path.dirname(os.path.abspath(args.output))
    if not os.path.isdir(out_dir):
        raise DumpError(f"{args.output}: folder {out_dir} does not exist")
    if os.path.exists(args.output):
        for role, path in (("weights", args.weights), ("input", args.input)):
            if os.path.samefile(args.output, path):
                raise DumpError(f"{args.output}: is the {role} file; refusing to overwrite it")
    torch = import_torch()
    if args.threads > 0:
        torch.set_num_threads(args.threads)
    state, metadata = load_weights(torch, args.weights)
    x = torch.from_numpy(x_np).float()
    model, forward, required = build(torch, args, state, metadata, x)
    load_state(torch, model, state, required, args.weights)
    recorder = Recorder(torch, model, keep)
    with torch.no_grad():
        y = forward(x)
    recorder.remove()
    tensors = dict(recorder.tensors)
    if args.outputs:  # asked for explicitly: not subject to --filter
        recorder.keep = lambda name: True
        for k, v in final_outputs(torch, args.model, y).items():
            recorder.tensors = {}
            recorder.add(k, v)
            tensors.update(recorder.tensors)
    if not tensors:
        raise DumpError(f"nothing to write: no module output matches --filter '{args.filter}'")
    metadata_out = {"dump.order": ",".join(tensors), "dump.source": "torch", "dump.model": args.model,
                    "dump.weights": os.path.basename(args.weights), "dump.torch": torch.__version__}
    try:
        safetensors_io.save(args.output, tensors, metadata_out)
    except OSError as e:
        raise DumpError(f"{args.output}: cannot write ({e.strerror or first_line(e)})") from e
    print(f"wrote {args.output}: {len(tensors)} tensors of {args.model} on input {list(x.shape)}")


def main(argv=None):
    args = parse_args(argv)
    try:
        run(args)
    except DumpError as e:
        print(f"{PROG}: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
