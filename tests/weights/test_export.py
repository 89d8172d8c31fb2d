#!/usr/bin/python3
"""Tests for weights/export.py: every checkpoint form it accepts, dtype options,
metadata, and one-line errors with exit code 1 for unreadable or unknown input.
Fails (never skips) when torch is missing.

Usage: test_export.py BUILD_DIR
"""

import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
WEIGHTS = os.path.normpath(os.path.join(HERE, "..", "..", "weights"))
EXPORT = os.path.join(WEIGHTS, "export.py")
HINT = "install python3-torch (apt-get install python3-torch)"

failures = []


def check(cond, what):
    if not cond:
        failures.append(what)
        print(f"FAIL: {what}", file=sys.stderr)


class Result:
    def __init__(self, returncode, stdout, stderr):
        self.returncode, self.stdout, self.stderr = returncode, stdout, stderr


def run_export(*args, separate_process=False):
    """Runs export.py; in this process by default (torch is imported once, which
    keeps the test fast), or as its own process to check real exit codes."""
    if separate_process:
        return subprocess.run([sys.executable, EXPORT, *args], capture_output=True, text=True)
    import contextlib
    import importlib.util
    import io

    spec = importlib.util.spec_from_file_location("roadnn_export", EXPORT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = module.main(list(args))
        except SystemExit as e:
            rc = e.code
    return Result(rc, out.getvalue(), err.getvalue())


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    try:
        import numpy as np
        import torch
        from torch import nn
    except ImportError as e:
        print(f"test_export.py: {HINT} ({e})", file=sys.stderr)
        return 1
    sys.path.insert(0, WEIGHTS)
    import safetensors_io

    work = os.path.join(sys.argv[1], "weights_export_test")
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)

    torch.manual_seed(0)
    model = nn.Sequential(nn.Conv2d(3, 8, 3), nn.BatchNorm2d(8), nn.ReLU(), nn.Flatten(),
                          nn.Linear(8 * 4 * 4, 4), nn.LayerNorm(4))
    model.train()
    model(torch.randn(2, 3, 6, 6))  # moves the BatchNorm running stats off their init values
    model.eval()
    state = model.state_dict()
    check("1.num_batches_tracked" in state, "test model lacks num_batches_tracked")
    expected = {k: v.numpy() for k, v in state.items() if not k.endswith("num_batches_tracked")}
    optimizer = torch.optim.SGD(model.parameters(), lr=0.1, momentum=0.9)

    def export_ok(name, obj, *extra, separate_process=False):
        ckpt = os.path.join(work, name + ".pt")
        out = os.path.join(work, name + ".safetensors")
        torch.save(obj, ckpt)
        r = run_export(ckpt, out, *extra, separate_process=separate_process)
        check(r.returncode == 0, f"{name}: exit {r.returncode}, stderr {r.stderr.strip()!r}")
        if r.returncode != 0:
            return None, None, r
        check(f"wrote {out}" in r.stdout, f"{name}: no summary line in {r.stdout!r}")
        tensors, meta = safetensors_io.load(out)
        check(meta.get("format") == "roadnn-v1", f"{name}: format metadata {meta}")
        check(meta.get("source") == name + ".pt", f"{name}: source metadata {meta}")
        return tensors, meta, r

    def same_as_model(name, tensors):
        if tensors is None:
            return
        check(list(tensors) == list(expected), f"{name}: names {list(tensors)}")
        for k, v in expected.items():
            if k in tensors:
                check(tensors[k].dtype == np.float32, f"{name}: {k} dtype {tensors[k].dtype}")
                check(np.array_equal(tensors[k], v), f"{name}: {k} values differ")
        check(not any("num_batches_tracked" in k or k.startswith("module.") for k in tensors),
              f"{name}: num_batches_tracked or module. left in {list(tensors)}")

    forms = {
        "bare": state,
        "model_state_dict": {"model_state_dict": state, "optimizer_state_dict": optimizer.state_dict(),
                             "epoch": 7},
        "state_dict": {"state_dict": state, "epoch": 7, "best_acc": 0.5},
        "module": model,
        "ddp": {"module." + k: v for k, v in state.items()},
        "ddp_wrapped": {"model_state_dict": {"module." + k: v for k, v in state.items()}},
    }
    for name, obj in forms.items():
        tensors, _, _ = export_ok(name, obj)
        same_as_model(name, tensors)
    # Once as a real process: exit code 0 and the same result.
    tensors, _, _ = export_ok("bare_process", state, separate_process=True)
    same_as_model("bare_process", tensors)

    # Non-float tensors other than num_batches_tracked are skipped with a warning.
    mixed = dict(state)
    mixed["anchors.index"] = torch.arange(3)
    mixed["mask"] = torch.tensor([True, False])
    tensors, _, r = export_ok("mixed", mixed)
    same_as_model("mixed", tensors)
    check("warning: skipped 2 non-float tensor(s): anchors.index (int64), mask (bool)" in r.stderr,
          f"mixed: warning missing: {r.stderr!r}")
    check("num_batches_tracked" not in r.stderr, "num_batches_tracked should be dropped silently")

    # Non-contiguous and float64 tensors become contiguous float32.
    odd = {"t": torch.arange(12, dtype=torch.float64).reshape(3, 4).t(), "s": torch.tensor(1.5)}
    tensors, _, _ = export_ok("odd", odd)
    if tensors is not None:
        check(np.array_equal(tensors["t"], np.arange(12, dtype=np.float32).reshape(3, 4).T), "transposed")
        check(tensors["t"].dtype == np.float32, "float64 not converted")
        check(tensors["s"].shape == () and tensors["s"] == 1.5, "scalar")

    # A submodule genuinely named "module" keeps its name when other keys lack the prefix.
    partial = {"module.w": torch.ones(2), "head.w": torch.zeros(2)}
    tensors, _, _ = export_ok("partial_prefix", partial)
    if tensors is not None:
        check(sorted(tensors) == ["head.w", "module.w"], f"partial prefix: {list(tensors)}")

    # --dtype and --metadata.
    tensors, meta, _ = export_ok("f16", state, "--dtype", "f16", "--metadata", "model=convnext",
                                 "note=a=b", "--metadata", "empty=")
    if tensors is not None:
        check(all(t.dtype == np.float16 for t in tensors.values()), "f16 dtype")
        for k, v in expected.items():
            check(np.array_equal(tensors[k], v.astype(np.float16)), f"f16 {k} values")
        check(meta.get("model") == "convnext" and meta.get("note") == "a=b" and meta.get("empty") == "",
              f"user metadata {meta}")
    tensors, _, _ = export_ok("bf16", state, "--dtype", "bf16")
    if tensors is not None:
        for k, v in state.items():
            if k in expected:
                want = v.to(torch.bfloat16).float().numpy()
                check(np.array_equal(tensors[k], want), f"bf16 {k} values")

    # Issue 14: --preset and --meta write the stixelnext.* settings; --meta wins over the
    # preset; a .safetensors input is re-exported with its metadata plus the new keys.
    tensors, meta, _ = export_ok("preset", state, "--preset", "coopscenes", "--meta", "stixelnext.head=v1")
    if tensors is not None:
        want = {"stixelnext.input_height": "1200", "stixelnext.input_width": "1920", "stixelnext.columns": "120",
                "stixelnext.stixel_width": "16", "stixelnext.normalization": "imagenet",
                "stixelnext.anchors": "tangent:4,66,64", "stixelnext.head": "v1"}
        check(all(meta.get(k) == v for k, v in want.items()), f"preset metadata {meta}")
    _, meta, _ = export_ok("preset_override", state, "--preset", "waymo", "--meta", "stixelnext.columns=120")
    if meta is not None:
        check(meta.get("stixelnext.columns") == "120" and meta.get("stixelnext.input_height") == "1280",
              f"--meta over --preset: {meta}")
    again = os.path.join(work, "again.safetensors")
    r = run_export(os.path.join(work, "preset.safetensors"), again, "--meta", "stixelnext.head=v3")
    check(r.returncode == 0, f"safetensors input: {r.stderr!r}")
    if r.returncode == 0:
        t2, m2 = safetensors_io.load(again)
        check(m2.get("stixelnext.head") == "v3" and m2.get("stixelnext.columns") == "120" and
              m2.get("source") == "preset.safetensors", f"re-exported metadata {m2}")
        check(sorted(t2) == sorted(expected), "re-exported tensors")
    # V1/V3-shaped heads without a declared head: a warning naming both and the fix.
    heads = {"classifier.attention_layer.query_layer.weight": torch.zeros(4, 4),
             "classifier.channel_reduce.weight": torch.zeros(192, 8, 1, 1)}
    def saved_heads(name):
        p = os.path.join(work, name + ".pt")
        torch.save(heads, p)
        return p

    r = run_export(saved_heads("v1v3"), os.path.join(work, "v1v3.safetensors"))
    check(r.returncode == 0 and "V1" in r.stderr and "V3" in r.stderr and "stixelnext.head=v1" in r.stderr,
          f"V1/V3 warning: {r.stderr!r}")
    r = run_export(saved_heads("v1v3_named"), os.path.join(work, "v1v3_named.safetensors"),
                   "--meta", "stixelnext.head=v3")
    check(r.returncode == 0 and "warning" not in r.stderr, f"declared head still warns: {r.stderr!r}")

    # Errors: exit 1, one line on stderr starting with the program name, no output file.
    def export_fails(name, ckpt, fragment, *extra, out=None, separate_process=False):
        out = out or os.path.join(work, name + ".safetensors")
        r = run_export(ckpt, out, *extra, separate_process=separate_process)
        check(r.returncode == 1, f"{name}: exit {r.returncode}, expected 1 (stderr {r.stderr!r})")
        lines = r.stderr.strip().splitlines()
        # Warnings may precede it; the error itself is the last line, and one line.
        check(lines and all(line.startswith("export.py: ") for line in lines) and
              "warning" not in lines[-1], f"{name}: stderr {r.stderr!r}")
        check(fragment in r.stderr, f"{name}: {r.stderr!r} lacks {fragment!r}")
        check(not os.path.exists(out), f"{name}: output file created")

    def saved(name, obj):
        p = os.path.join(work, name + ".pt")
        torch.save(obj, p)
        return p

    export_fails("missing", os.path.join(work, "nope.pt"), "nope.pt: no such file")
    export_fails("directory", work, "is a directory")
    garbage = os.path.join(work, "garbage.pt")
    with open(garbage, "wb") as f:
        f.write(b"this is not a checkpoint\n" * 10)
    export_fails("garbage", garbage, "garbage.pt: cannot load checkpoint")
    export_fails("garbage_process", garbage, "garbage.pt: cannot load checkpoint", separate_process=True)
    empty_file = os.path.join(work, "empty_file.pt")
    open(empty_file, "wb").close()
    export_fails("empty_file", empty_file, "cannot load checkpoint")
    export_fails("int", saved("int", 5), "unsupported checkpoint content: int")
    export_fails("no_state", saved("no_state", {"epoch": 3, "lr": 0.1}),
                 "no state dict found (expected a state_dict")
    export_fails("empty_dict", saved("empty_dict", {}), "empty dict")
    export_fails("only_ints", saved("only_ints", {"a.num_batches_tracked": torch.tensor(1),
                                                  "idx": torch.arange(2)}), "no float tensors")
    export_fails("nan", saved("nan", {"w": torch.tensor([1.0, float("nan")])}), "'w' contains NaN or Inf")
    export_fails("f16_overflow", saved("f16_overflow", {"big": torch.tensor([1e6])}),
                 "'big' has values outside the range of float16", "--dtype", "f16")
    export_fails("reserved", saved("reserved", state), "'format' is reserved", "--metadata", "format=x")
    export_fails("bad_metadata", saved("bad_metadata", state), "expects KEY=VALUE", "--metadata", "oops")
    export_fails("bad_head", saved("bad_head", state), "expected one of v0, v1, v2, v3, v4",
                 "--meta", "stixelnext.head=v5")
    export_fails("unknown_key", saved("unknown_key", state), "is not a stixelnext setting",
                 "--meta", "stixelnext.colums=240")
    export_fails("bad_int", saved("bad_int", state), "expected a positive integer",
                 "--meta", "stixelnext.columns=-3")
    export_fails("unwritable", saved("unwritable", state), "cannot write",
                 out=os.path.join(work, "no_dir", "x.safetensors"))
    check(not os.path.exists(os.path.join(work, "no_dir")), "unwritable: directory created")

    # detectron2: the trainer's model_final.pth ({"model", "trainer", "iteration"}; the
    # trainer entry holds no tensors the state dict needs) and the model zoo's .pkl, a
    # plain pickle of numpy arrays.
    trainer = {"model": state, "trainer": {"iteration": 89999, "hooks": {"LRScheduler": {
        "base_lrs": [0.02], "last_epoch": 90000}}, "_trainer": {"optimizer": optimizer.state_dict()}},
        "iteration": 89999}
    tensors, _, r = export_ok("d2_trainer", trainer)
    same_as_model("d2_trainer", tensors)
    check("from 'model'" in r.stdout, f"d2_trainer: form in {r.stdout!r}")
    import pickle
    pkl = os.path.join(work, "d2_zoo.pkl")
    with open(pkl, "wb") as f:
        pickle.dump({"model": {k: v.numpy() for k, v in state.items()}, "__author__": "Detectron2 Model Zoo",
                     "matching_heuristics": True}, f)
    r = run_export(pkl, os.path.join(work, "d2_zoo.safetensors"), separate_process=True)
    check(r.returncode == 0, f"d2_zoo: exit {r.returncode}, stderr {r.stderr.strip()!r}")
    if r.returncode == 0:
        zoo, _ = safetensors_io.load(os.path.join(work, "d2_zoo.safetensors"))
        same_as_model("d2_zoo", zoo)
        # num_batches_tracked (an int64 array) is dropped as for tensors
        check("warning" not in r.stderr, f"d2_zoo: unexpected warning {r.stderr!r}")
    # A pickle that is neither a checkpoint nor loadable says so on one line.
    bad_pkl = os.path.join(work, "d2_truncated.pkl")
    with open(pkl, "rb") as f, open(bad_pkl, "wb") as g:
        g.write(f.read()[:200])
    export_fails("d2_truncated", bad_pkl, "d2_truncated.pkl: cannot load checkpoint")
    nan_pkl = os.path.join(work, "d2_nan.pkl")
    with open(nan_pkl, "wb") as f:
        pickle.dump({"model": {"w": np.array([1.0, np.nan], dtype=np.float32)}}, f)
    export_fails("d2_nan", nan_pkl, "'w' contains NaN or Inf")
    obj_pkl = os.path.join(work, "d2_objects.pkl")
    with open(obj_pkl, "wb") as f:
        pickle.dump({"model": {"w": np.array(["a", "b"], dtype=object)}}, f)
    export_fails("d2_objects", obj_pkl, "array 'w': cannot convert")

    # A pickled module whose class cannot be imported is an error, not a crash.
    custom = os.path.join(work, "custom.pt")
    script = ("import sys, torch\n"
              "class Net(torch.nn.Module):\n"
              "    def __init__(self):\n"
              "        super().__init__(); self.fc = torch.nn.Linear(2, 2)\n"
              "torch.save(Net(), sys.argv[1])\n")
    made = subprocess.run([sys.executable, "-c", script, custom], capture_output=True, text=True)
    check(made.returncode == 0, f"could not build custom checkpoint: {made.stderr}")
    export_fails("custom", custom, "save its state_dict() instead", separate_process=True)

    # Without torch, export.py and the test scripts fail with the install hint.
    blocker = ("import runpy, sys; sys.modules['torch'] = None; script = sys.argv[1]; "
               "sys.argv = sys.argv[1:]; runpy.run_path(script, run_name='__main__')")
    for script, args in ((EXPORT, [os.path.join(work, "bare.pt"), os.path.join(work, "nt.safetensors")]),
                         (os.path.abspath(__file__), [work]),
                         (os.path.join(HERE, "test_safetensors_io.py"), [work]),
                         (os.path.join(HERE, "write_python_safetensors.py"), ["--out", work])):
        r = subprocess.run([sys.executable, "-c", blocker, script, *args], capture_output=True, text=True)
        check(r.returncode == 1 and HINT in r.stderr,
              f"{os.path.basename(script)} without torch: exit {r.returncode}, stderr {r.stderr!r}")
    check(not os.path.exists(os.path.join(work, "nt.safetensors")), "output written without torch")

    # --help explains the trust issue; usage errors exit 2.
    r = subprocess.run([sys.executable, EXPORT, "--help"], capture_output=True, text=True)
    check(r.returncode == 0 and "pickles" in r.stdout and "trust" in r.stdout, f"--help: {r.stdout!r}")
    r = subprocess.run([sys.executable, EXPORT], capture_output=True, text=True)
    check(r.returncode == 2, f"no arguments: exit {r.returncode}")
    r = run_export(os.path.join(work, "bare.pt"), os.path.join(work, "x.safetensors"), "--dtype", "f8",
                   separate_process=True)
    check(r.returncode == 2, f"bad --dtype: exit {r.returncode}")

    if failures:
        print(f"test_export.py: {len(failures)} failure(s)", file=sys.stderr)
        return 1
    print("test_export.py: all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
