"""Reference stixel extraction ("revert") in numpy, written from the
specification (reference stixelnext.md, section 3): for random predictions
[A, N, U] it writes the prediction and the stixels the reference code would
emit, with each stixel's candidate index n.

The arithmetic follows the reference code on numpy 1.x: the prediction is a
float32 array, a candidate's values are numpy float32 scalars, `v * H + 1` with a
Python int H promotes to float64 (exact), `P >= prob` compares in float64,
`anchor * exp(d_res)` takes the float32 exp times the float64 anchor, and the
protobuf message stores d and confidence as float32."""
import sys

import stixel_refutil as ru

np = ru.import_numpy()


def decode_depth_residual(d_res, anchor, eps=1e-6):
    """The authors' decoding, in numpy float64 as they run it."""
    anchor = max(float(anchor), eps)
    return float(np.exp(np.log(anchor) + float(d_res)))


def revert(pred, anchors, img_height, prob, u_scale):
    A = pred.shape[0]
    columns = np.transpose(pred, (2, 1, 0))  # "a n u -> u n a"
    rows = []
    for u in range(len(columns)):
        for n in range(len(columns[u])):
            c = columns[u][n]
            p = c[A - 1]
            if not (p >= prob):
                continue
            vT = int(c[1] * img_height + 1)
            vB = int(c[0] * img_height + 1)
            if A == 4:
                d = decode_depth_residual(c[2], anchors[n])
            else:
                d = anchors[n]
            rows.append((u * u_scale, vT, vB, np.float32(d), np.float32(p), n))
    return rows


def case(name, A, U, H, width, prob, anchors, seed, out):
    rng = np.random.default_rng(seed)
    N = len(anchors)
    pred = rng.random((A, N, U), dtype=np.float32)
    if A == 4:
        pred[2] *= np.float32(0.2)  # residuals in the trained range (~0..0.12)
    # Candidates exactly at the threshold, saturated sigmoids, exact rows.
    flat = pred[A - 1].reshape(-1)
    flat[rng.choice(flat.size, 20, replace=False)] = np.float32(prob)
    pred[1, 0, :4] = [0.0, 1.0, 0.5, 0.25]
    pred[A - 1, 0, :4] = 1.0
    if name.endswith("nan"):
        flat[rng.choice(flat.size, 5, replace=False)] = np.nan
    rows = revert(pred, anchors, H, prob, width)
    out_rows = np.array([r[:3] for r in rows], dtype=np.int32).reshape(-1, 3)
    ru.save("%s/stixel_extract_%s.safetensors" % (out, name), {
        "prediction": pred,
        "anchors": anchors.astype(np.float32),
        "anchors_f64": anchors,
        "u_vT_vB": out_rows,
        "d": np.array([r[3] for r in rows], dtype=np.float32),
        "confidence": np.array([r[4] for r in rows], dtype=np.float32),
        "n": np.array([r[5] for r in rows], dtype=np.int32),
    }, {"attrs": A, "height": H, "width": width, "threshold": repr(float(prob))})
    return len(rows)


def main(argv):
    a = ru.args(argv)
    tangent = ru.tangent_anchors(np)
    linear = ru.linear_anchors(np, 5.0, 69.0, 64)
    ru.save(a.out + "/stixel_anchors.safetensors", {
        "tangent": tangent.astype(np.float32), "tangent_f64": tangent,
        "linear_5_69": linear.astype(np.float32)})
    counts = {
        "v4_all": case("v4_all", 4, 240, 1280, 8, 0.0, tangent, 1, a.out),
        "v4_036": case("v4_036", 4, 240, 1280, 8, 0.36, tangent, 2, a.out),
        "v3_036_nan": case("v3_036_nan", 3, 240, 1280, 8, 0.36, tangent, 3, a.out),
        "v1_coop": case("v1_coop", 3, 120, 1200, 16, 0.33, linear, 4, a.out),
    }
    print("stixel extraction references:", counts)


if __name__ == "__main__":
    main(sys.argv[1:])
