#!/usr/bin/python3
"""Tests for scripts/torch_dump.py on the files the reference scripts wrote (fixtures
ref_convnext_ref, ref_stixel_head_ref, ref_detector_ref):
  - its final outputs (--outputs) equal the reference scripts' for a ConvNeXt config read
    from the weights, StixelNExT++ V4 and V1, and Faster R-CNN MobileNetV3-320;
  - the dump follows the contract: root not dumped, '#k' for repeated calls, '[i]' and
    '[key]' for structured outputs, ImageList as its tensors, int64 labels, dump.order
    in call order, dump.source/dump.model;
  - .pth checkpoints ({"model_state_dict": ...}) give the same dump as safetensors;
  - errors are one line with exit code 1 naming the file.
Fails (never skips) when torch or a reference file is missing.

Usage: test_torch_dump.py REF_DIR
"""
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
TORCH_DUMP = os.path.normpath(os.path.join(HERE, "..", "..", "scripts", "torch_dump.py"))
import refcommon  # noqa: E402  (exits with the install hint without numpy)
import safetensors_io  # noqa: E402  (weights/, on the path through refcommon)

failures = []


def check(cond, what):
    if not cond:
        failures.append(what)
        print(f"FAIL: {what}", file=sys.stderr)


def run(*args):
    return subprocess.run([sys.executable, TORCH_DUMP, *args, "--threads", "2"], capture_output=True, text=True)


def need(path):
    if not os.path.exists(path):
        sys.exit(f"error: {path} is missing: its generator (a ctest fixture ref_*) failed or did not run; "
                 + refcommon.INSTALL_HINT)
    return path


def close(a, b, rel):
    import numpy as np
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    if a.shape != b.shape:
        return False
    scale = max(float(np.abs(b).max()) if b.size else 0.0, 1e-30)
    return float(np.abs(a - b).max() if a.size else 0.0) <= rel * scale


def dump(tmp, name, model, weights, inp, *extra):
    out = os.path.join(tmp, name)
    r = run("--model", model, "--weights", weights, "--input", inp, "--output", out, *extra)
    check(r.returncode == 0, f"{name}: exit {r.returncode}: {r.stderr.strip()}")
    if r.returncode != 0:
        return {}, {}
    return safetensors_io.load(out)


def test_outputs_match_the_references(ref, tmp):
    # ConvNeXt, widths and depths from the weights (the odd 4-stage test config).
    case, _ = safetensors_io.load(need(f"{ref}/convnext_case_odd_cfg.safetensors"))
    t, md = dump(tmp, "cn.st", "convnext", need(f"{ref}/convnext_small_cfg_weights.safetensors"),
                 f"{ref}/convnext_case_odd_cfg.safetensors", "--outputs")
    if t:
        check(close(t["features"], case["expected"], 1e-6), "convnext: features differ from convnext_ref.py")
        check(close(t["features.7"], case["expected"], 1e-6), "convnext: features.7 is not the stage output")
        order = md["dump.order"].split(",")
        check(order[:3] == ["features.0.0", "features.0.1", "features.0"], f"convnext: order starts {order[:3]}")
        check(order.index("features.1.0.block.3") < order.index("features.1.0") < order.index("features.2.0"),
              "convnext: dump.order is not the call order")
        check(t["features.1.0.block.3"].shape[-1] == 4 * 20 and t["features.1.0.block.3"].ndim == 4,
              f"convnext: block.3 is not NHWC [N,H,W,4C]: {t['features.1.0.block.3'].shape}")
        check("" not in t and md["dump.source"] == "torch" and md["dump.model"] == "convnext",
              f"convnext: metadata {md}")
    # StixelNExT++ V4 and V1 at 256x640 (U = 80).
    for v in ("v4", "v1"):
        case, _ = safetensors_io.load(need(f"{ref}/stixel_case_{v}_small.safetensors"))
        t, md = dump(tmp, f"st_{v}.st", "stixelnext", need(f"{ref}/stixel_{v}_weights.safetensors"),
                     f"{ref}/stixel_case_{v}_small.safetensors", "--outputs")
        if t:
            check(close(t["prediction"], case["expected"], 1e-6), f"stixelnext {v}: prediction differs")
            check(close(t["classifier"], case["expected"], 0), f"stixelnext {v}: classifier is not the prediction")
            head = "classifier.local_mixing.depthwise" if v == "v4" else "classifier.attention_layer.query_layer"
            check(head in t and "features.7" in t, f"stixelnext {v}: {head} or features.7 missing")
    # Faster R-CNN MobileNetV3-Large 320 on the odd-sized image.
    case, _ = safetensors_io.load(need(f"{ref}/det_mnv3_320_odd.safetensors"))
    t, md = dump(tmp, "det.st", "fasterrcnn_mobilenet_v3_large_320_fpn", need(f"{ref}/det_mnv3_320_weights.safetensors"),
                 f"{ref}/det_mnv3_320_odd.safetensors", "--outputs")
    if t:
        check(close(t["transform[0]"], case["transformed"], 0), "detector: transform[0] (ImageList.tensors) differs")
        check(close(t["rpn[0][0]"], case["proposals"], 1e-5), "detector: rpn[0][0] differs from the proposals")
        check(close(t["boxes"], case["boxes"], 1e-5), "detector: boxes differ")
        check((t["labels"] == case["labels"]).all() and t["labels"].dtype.kind == "i", "detector: labels differ")
        for name in ("rpn.head.cls_logits", "rpn.head.cls_logits#1", "rpn.head.cls_logits#2", "rpn.head[0][2]",
                     "backbone.fpn[pool]", "backbone[0]", "roi_heads.box_roi_pool", "roi_heads[0][0][labels]"):
            check(name in t, f"detector: no tensor {name}")
        if "rpn.head.cls_logits#2" in t:
            check(close(t["rpn.head[0][2]"], t["rpn.head.cls_logits#2"], 0), "detector: rpn.head[0][2] != cls_logits#2")
        check(t["roi_heads.box_head"].ndim == 2 and t["roi_heads.box_head"].shape[1] == 1024,
              "detector: box head is not [R, 1024]")


def test_checkpoint_and_filter(ref, tmp):
    import torch
    st, _ = safetensors_io.load(need(f"{ref}/convnext_small_cfg_weights.safetensors"))
    pth = os.path.join(tmp, "ckpt.pth")
    torch.save({"model_state_dict": {k: torch.from_numpy(v) for k, v in st.items()}, "epoch": 3}, pth)
    a, _ = dump(tmp, "a.st", "convnext", f"{ref}/convnext_small_cfg_weights.safetensors",
                f"{ref}/convnext_case_odd_cfg.safetensors", "--filter", r"^features\.[0-9]$")
    b, md = dump(tmp, "b.st", "convnext", pth, f"{ref}/convnext_case_odd_cfg.safetensors", "--filter",
                 r"^features\.[0-9]$")
    check(sorted(a) == [f"features.{i}" for i in range(8)], f"--filter kept {sorted(a)}")
    check(sorted(a) == sorted(b) and all((a[k] == b[k]).all() for k in a), ".pth and safetensors dumps differ")


def test_errors(ref, tmp):
    w = f"{ref}/convnext_small_cfg_weights.safetensors"
    x = f"{ref}/convnext_case_odd_cfg.safetensors"
    out = os.path.join(tmp, "never.st")
    st, _ = safetensors_io.load(w)
    bad_shape = os.path.join(tmp, "bad_shape.st")
    st["features.1.0.block.3.weight"] = st["features.1.0.block.3.weight"][:, :5]
    safetensors_io.save(bad_shape, st)
    no_input = os.path.join(tmp, "no_input.st")
    safetensors_io.save(no_input, {"x": st["features.0.0.bias"]})
    truncated = os.path.join(tmp, "truncated.st")
    with open(w, "rb") as f, open(truncated, "wb") as g:
        g.write(f.read()[:-10])
    cases = [
        (("--model", "convnext", "--weights", os.path.join(tmp, "absent.st"), "--input", x), "absent.st"),
        (("--model", "convnext", "--weights", truncated, "--input", x), "truncated.st"),
        (("--model", "convnext", "--weights", bad_shape, "--input", x), "features.1.0.block.3.weight"),
        (("--model", "convnext", "--weights", w, "--input", no_input), "no tensor 'input'"),
        (("--model", "convnext", "--weights", w, "--input", w), "no tensor 'input'"),
        (("--model", "convnext_tiny", "--weights", w, "--input", x), "missing tensor"),
        (("--model", "stixelnext", "--weights", w, "--input", x), "no StixelNExT++ head"),
        (("--model", "fasterrcnn_resnet50_fpn", "--weights", w, "--input", x), "cls_score"),
        (("--model", "convnext", "--weights", w, "--input", x, "--filter", "("), "--filter"),
        (("--model", "convnext", "--weights", w, "--input", x, "--filter", "^nothing$"), "nothing to write"),
    ]
    r = run("--model", "convnext", "--weights", w, "--input", x, "--output", x)
    check(r.returncode == 1 and "is the input file" in r.stderr, f"output = input: {r.stderr!r}")
    for args, expect in cases:
        r = run(*args, "--output", out)
        check(r.returncode == 1, f"{args}: exit {r.returncode}, expected 1: {r.stderr.strip()}")
        lines = [line for line in r.stderr.splitlines() if "warning" not in line]
        check(len(lines) == 1 and expect in lines[0], f"{args}: expected one line with '{expect}': {r.stderr!r}")
        check(not os.path.exists(out), f"{args}: left an output file")
    r = subprocess.run([sys.executable, TORCH_DUMP, "--help"], capture_output=True, text=True)
    check(r.returncode == 0 and "--filter" in r.stdout and "named_modules" in r.stdout, "--help")


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: test_torch_dump.py REF_DIR")
    refcommon.import_torch()
    ref = sys.argv[1]
    with tempfile.TemporaryDirectory() as tmp:
        test_outputs_match_the_references(ref, tmp)
        test_checkpoint_and_filter(ref, tmp)
        test_errors(ref, tmp)
    if failures:
        sys.exit(f"{len(failures)} check(s) failed")
    print("torch_dump.py: all checks passed")


if __name__ == "__main__":
    main()
