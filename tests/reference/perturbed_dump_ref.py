#!/usr/bin/python3
"""Dumps of a checkpoint and of the same checkpoint with one tensor perturbed, both
written by scripts/torch_dump.py, for the nncompare test that must name the first
module downstream of the perturbed tensor. Writes into --out:
  perturbed_weights.safetensors          seeded convnext_tiny state_dict (features.*)
  perturbed_weights_changed.safetensors  the same with PERTURBED scaled by 1.01
  perturbed_input.safetensors            'input' [1,3,64,96] (and raw as perturbed_input.f32)
  perturbed_original.dump.safetensors    torch_dump.py on the original weights
  perturbed_changed.dump.safetensors     torch_dump.py on the perturbed weights"""
import os
import subprocess
import sys

import refcommon
import torch_models  # weights/, on the path through refcommon

PERTURBED = "features.3.1.block.3.weight"  # stage 2, block 1, the first pointwise Linear
SCALE = 1.01
TORCH_DUMP = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts", "torch_dump.py")


def main():
    out, _ = refcommon.out_dir(sys.argv[1:])
    torch = refcommon.import_torch()
    model = refcommon.init_weights(torch_models.convnext(torch, "convnext_tiny"), seed=77)
    sd = {k: v for k, v in model.state_dict().items() if k.startswith("features.")}
    refcommon.save(f"{out}/perturbed_weights.safetensors", sd)
    changed = dict(sd)
    changed[PERTURBED] = sd[PERTURBED] * SCALE
    refcommon.save(f"{out}/perturbed_weights_changed.safetensors", changed, {"perturbed": PERTURBED})
    x = torch.randn((1, 3, 64, 96), generator=torch.Generator().manual_seed(5))
    refcommon.save(f"{out}/perturbed_input.safetensors", {"input": x})
    x.numpy().astype("<f4").tofile(f"{out}/perturbed_input.f32")  # for examples/check_convnext
    for weights, dump in (("perturbed_weights", "perturbed_original"), ("perturbed_weights_changed", "perturbed_changed")):
        cmd = [sys.executable, TORCH_DUMP, "--model", "convnext_tiny", "--weights", f"{out}/{weights}.safetensors",
               "--input", f"{out}/perturbed_input.safetensors", "--output", f"{out}/{dump}.dump.safetensors",
               "--threads", "2"]
        if subprocess.run(cmd).returncode != 0:
            sys.exit(f"error: {' '.join(cmd)} failed")
    print(f"perturbed {PERTURBED} x{SCALE}: dumps written")


if __name__ == "__main__":
    main()
