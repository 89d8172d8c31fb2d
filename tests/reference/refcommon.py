"""Shared helpers of the PyTorch reference scripts: torch import with an install
hint, seeded weight initialisation at the project's scales, safetensors output."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "weights"))

INSTALL_HINT = ("PyTorch reference outputs need Debian's python3-torch and python3-torchvision for "
                "/usr/bin/python3: apt-get install -y python3-torch python3-torchvision python3-numpy")
try:
    import safetensors_io  # noqa: E402  (numpy)
except ImportError as e:
    sys.exit("error: %s (%s)" % (INSTALL_HINT, e))


def import_torch():
    try:
        import torch  # noqa: F401
        import torchvision  # noqa: F401
    except ImportError as e:
        sys.exit("error: %s (%s)" % (INSTALL_HINT, e))
    import torch
    torch.set_num_threads(max(1, min(2, os.cpu_count() or 1)))
    return torch


def init_weights(module, seed):
    """Seeded weights that make every layer matter: conv/linear N(0, 1/fan_in),
    layer scale U(0.3, 1), norm gamma N(1, 0.2) and beta N(0, 0.1), biases N(0, 0.05)."""
    import torch
    g = torch.Generator().manual_seed(seed)
    with torch.no_grad():
        for name, p in module.named_parameters():
            leaf = name.rsplit(".", 1)[-1]
            owner = module.get_submodule(name.rsplit(".", 1)[0]) if "." in name else module
            is_norm = isinstance(owner, (torch.nn.LayerNorm, torch.nn.BatchNorm2d, torch.nn.GroupNorm)) \
                or type(owner).__name__ in ("LayerNorm2d", "FrozenBatchNorm2d")
            if leaf == "layer_scale":
                p.copy_(torch.rand(p.shape, generator=g) * 0.7 + 0.3)
            elif is_norm and leaf == "weight":
                p.copy_(1.0 + 0.2 * torch.randn(p.shape, generator=g))
            elif is_norm and leaf == "bias":
                p.copy_(0.1 * torch.randn(p.shape, generator=g))
            elif leaf == "bias":
                p.copy_(0.05 * torch.randn(p.shape, generator=g))
            else:
                fan_in = p[0].numel() if p.dim() > 1 else p.numel()
                p.copy_(torch.randn(p.shape, generator=g) / fan_in ** 0.5)
    return module


def save(path, tensors, metadata=None):
    """Writes a dict of torch tensors / numpy arrays as safetensors (atomically)."""
    safetensors_io.save(path, {k: (v.detach().contiguous() if hasattr(v, "detach") else v)
                               for k, v in tensors.items()}, metadata or {})


def small_sizes():
    """ROADNN_TEST_SIZES=small (CMake sets it on every test of a cross build, whose tests
    run under emulation; docs/ENGINEERING.md): write only the cases the tests run at small
    sizes (the tests of large inputs skip and say so)."""
    return os.environ.get("ROADNN_TEST_SIZES", "full") == "small"


def out_dir(argv):
    import argparse
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", required=True, help="folder for the reference files")
    ap.add_argument("rest", nargs="*")
    args = ap.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    return args.out, args.rest
