#!/usr/bin/python3
"""Writes weights_python.safetensors with safetensors_io.py for the C++ reader test
(tests/weights/test_python_file.cpp checks the same values).

Usage: write_python_safetensors.py --out DIR
"""

import argparse
import os
import sys

HINT = "install python3-torch (apt-get install python3-torch)"


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", required=True, help="directory for weights_python.safetensors")
    args = parser.parse_args()
    try:
        import numpy as np
        import torch
    except ImportError as e:
        print(f"write_python_safetensors.py: {HINT} ({e})", file=sys.stderr)
        return 1
    here = os.path.dirname(os.path.abspath(__file__))
    sys.path.insert(0, os.path.join(here, "..", "..", "weights"))
    import safetensors_io

    tensors = {
        "f32": np.arange(24, dtype=np.float32).reshape(2, 3, 4) * np.float32(0.25) - np.float32(1),
        "f16": np.array([1, -2, 65504, 2.0**-24, 0.1], dtype=np.float16),
        "bf16": torch.tensor([1.0, -3.0, 0.1, 3e38], dtype=torch.bfloat16),
        "i64": np.array([-(2**62), 0, 7], dtype=np.int64),
        "i32": np.array([[-5, 6]], dtype=np.int32),
        "u8": np.arange(5, dtype=np.uint8),
        "scalar": np.float32(3.5),
        "empty": np.zeros((0, 4), dtype=np.float32),
        "big_endian": np.arange(4, dtype=">f4"),  # must be stored little-endian
        "torch_f32": torch.linspace(-1, 1, 5),
    }
    metadata = {"format": "roadnn-v1", "writer": "safetensors_io.py", "unicode": "stra\u00dfe"}
    os.makedirs(args.out, exist_ok=True)
    safetensors_io.save(os.path.join(args.out, "weights_python.safetensors"), tensors, metadata)
    return 0


if __name__ == "__main__":
    sys.exit(main())
