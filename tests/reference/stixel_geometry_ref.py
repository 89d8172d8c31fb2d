"""3D points, boxes and the depth map of a Stixel World with pyStixel-lib's
formulas, written from the specification (reference stixelnext.md, sections 4-5):
X_h = inverse(K4 @ T) @ [u*d, v*d, d, 1] with the image vector in float32 (u*d
and v*d rounded to float32) and the inverse and product in float64."""
import sys

import stixel_refutil as ru

np = ru.import_numpy()


def project(K, T, u, v, d):
    img = np.ones((len(u), 4), dtype=np.float32)
    img[:, 0] = u
    img[:, 1] = v
    img[:, 2] = d
    img[:, :2] *= img[:, 2:3]
    k_exp = np.eye(4)
    k_exp[:3, :3] = np.array(K, dtype=np.float32).astype(np.float64).reshape(3, 3)
    P = k_exp @ np.array(T, dtype=np.float32).astype(np.float64).reshape(4, 4)
    return (np.linalg.inv(P) @ img.T).T[:, :3]


def point_cloud(K, T, u, vT, vB, d):
    uu, vv, dd = [], [], []
    for i in range(len(u)):
        for v in range(vT[i], vB[i]):
            uu.append(u[i])
            vv.append(v)
            dd.append(d[i])
    return project(K, T, np.array(uu, np.float32), np.array(vv, np.float32), np.array(dd, np.float32))


def boxes(K, T, u, vT, vB, d, conf, cluster, min_size=2, include_noise=False):
    groups = {}
    for i in range(len(u)):
        if cluster[i] < 0 and not include_noise:
            continue
        groups.setdefault(int(cluster[i]), []).append(i)
    out = []
    for cid in sorted(groups):
        idx = groups[cid]
        if len(idx) < min_size:
            continue
        uu = np.repeat(u[idx], 2).astype(np.float32)
        vv = np.stack([vT[idx], vB[idx]], 1).reshape(-1).astype(np.float32)
        dd = np.repeat(d[idx], 2).astype(np.float32)
        pts = project(K, T, uu, vv, dd)
        lo, hi = pts.min(0), pts.max(0)
        (x0, y0, z0), (x1, y1, z1) = lo, hi
        corners = np.array([[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0],
                            [x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]], dtype=np.float32)
        out.append((cid, len(idx), np.float32(np.mean(conf[idx].astype(np.float64))), corners))
    return out


def depth_map(W, H, u, vT, vB, d, width):
    m = np.full((H, W), np.inf, dtype=np.float32)
    for i in range(len(u)):
        off = int(width[i] // 2)
        left = max(0, int(u[i] - off))
        right = min(W - 1, int(u[i] + off))
        top = max(0, int(min(vT[i], vB[i])))
        bottom = min(H - 1, int(max(vT[i], vB[i])))
        if right <= left or bottom <= top:
            continue
        m[top:bottom + 1, left:right + 1] = np.minimum(m[top:bottom + 1, left:right + 1], np.float32(d[i]))
    m[np.isinf(m)] = np.nan
    return m


def world(rng, n, W, H):
    u = (rng.integers(0, W // 8, n) * 8).astype(np.int32)
    vT = rng.integers(-5, H, n).astype(np.int32)
    vB = (vT + rng.integers(-10, 200, n)).astype(np.int32)
    d = rng.uniform(4.0, 66.0, n).astype(np.float32)
    width = rng.choice([8, 8, 8, 5, 16, 0], n).astype(np.int32)
    conf = rng.random(n, dtype=np.float32)
    cluster = rng.integers(-1, 12, n).astype(np.int32)
    return u, vT, vB, d, width, conf, cluster


def rotation(rng):
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def main(argv):
    a = ru.args(argv)
    rng = np.random.default_rng(11)
    W, H = 640, 360
    # Optical frame (standard K, T = I) and Waymo vehicle frame (K_eff, T = a
    # rotated and shifted vehicle -> camera transform).
    calibs = {
        "optical": ([1000.5, 0.0, 320.25, 0.0, 998.0, 180.5, 0.0, 0.0, 1.0], list(np.eye(4).reshape(-1))),
    }
    ext = np.eye(4)
    ext[:3, :3] = rotation(rng) * 0.05 + np.eye(3)
    ext[:3, 3] = [1.545, -0.05, 2.115]
    T = np.linalg.inv(ext)
    calibs["waymo"] = ([320.25, -1000.5, 0.0, 180.5, 0.0, -1000.5, 1.0, 0.0, 0.0], list(T.reshape(-1)))
    for name, (K, T) in calibs.items():
        K32 = np.array(K, dtype=np.float32)
        T32 = np.array(T, dtype=np.float32)
        u, vT, vB, d, width, conf, cluster = world(rng, 400, W, H)
        top = project(K32, T32, u, vT, d)
        bottom = project(K32, T32, u, vB, d)
        cloud = point_cloud(K32, T32, u, vT, vB, d)
        bx = boxes(K32, T32, u, vT, vB, d, conf, cluster)
        bx_all = boxes(K32, T32, u, vT, vB, d, conf, cluster, 1, True)
        tensors = {
            "K": K32, "T": T32, "u": u, "vT": vT, "vB": vB, "d": d, "width": width,
            "confidence": conf, "cluster": cluster, "top": top, "bottom": bottom, "cloud": cloud,
            "depth_map": depth_map(W, H, u, vT, vB, d, width),
        }
        for tag, bb in (("boxes", bx), ("boxes_all", bx_all)):
            tensors[tag + "_id"] = np.array([b[0] for b in bb], dtype=np.int32)
            tensors[tag + "_count"] = np.array([b[1] for b in bb], dtype=np.int32)
            tensors[tag + "_confidence"] = np.array([b[2] for b in bb], dtype=np.float32)
            tensors[tag + "_corners"] = np.stack([b[3] for b in bb]).astype(np.float32)
        ru.save("%s/stixel_geometry_%s.safetensors" % (a.out, name), tensors,
                {"image_width": W, "image_height": H})
    print("stixel geometry references written")


if __name__ == "__main__":
    main(sys.argv[1:])
