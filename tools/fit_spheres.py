#!/usr/bin/env python3
"""Dev-only: fit and verify conservative collision spheres for the LBR iiwa 14 R820.

Reads the STL link meshes that the `pybullet` PyPI package ships
(`pybullet_data/kuka_iiwa/meshes/link_{0..7}.stl`, link frames = URDF link frames) and

1. fits K spheres per link: every triangle is assigned to the sphere whose centre minimises the
   triangle's farthest vertex, and each radius covers all vertices of its triangles plus a margin.
   A sphere is convex, so a triangle whose three vertices lie in it lies in it entirely: the
   whole mesh surface is inside the union (not only the vertices);
2. verifies that claim independently on dense samples of every triangle;
3. writes the committed fixture `shared/tests/data/iiwa14_mesh_points.csv` (a subsample of
   surface points, the tightest ones included) that the Rust test `spheres_cover_meshes` checks
   against the built-in model, and
4. writes `shared/tests/data/iiwa14_fk_pybullet.csv`: link frames computed by Bullet for random
   configurations, the independent FK reference of the Rust test `fk_matches_pybullet`.

Usage: pip install numpy pybullet && python3 tools/fit_spheres.py [--print-rust]
Nothing in the product calls this script; its results are committed.
"""
import argparse
import os
import struct
import sys

import numpy as np

# Spheres per link (link 0 = arm base flange, ... link 7 = last link).
SPHERES_PER_LINK = [2, 3, 3, 3, 3, 3, 2, 2]
MARGIN = 0.002  # m, added to every radius; also absorbs rounding to 1 mm
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT_DIR = os.path.join(ROOT, "shared", "tests", "data")


def mesh_dir():
    import pybullet_data

    return os.path.join(pybullet_data.getDataPath(), "kuka_iiwa", "meshes")


def load_stl(path):
    data = open(path, "rb").read()
    (n,) = struct.unpack("<I", data[80:84])
    if 84 + 50 * n != len(data):
        sys.exit(f"{path}: not a binary STL")
    rec = np.frombuffer(data[84:], dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]))
    return rec["v"].astype(np.float64)  # (n, 3, 3)


def fit(tris, k):
    verts = tris.reshape(-1, 3)
    mean = verts.mean(axis=0)
    _, _, vt = np.linalg.svd(verts - mean, full_matrices=False)
    axis = vt[0]
    s = (verts - mean) @ axis
    lo, hi = np.percentile(s, 5), np.percentile(s, 95)
    centres = np.array([mean + axis * (lo + (hi - lo) * (i + 0.5) / k) for i in range(k)])
    best = None
    for _ in range(60):
        # farthest vertex of each triangle from each centre: (n_tri, k)
        d = np.linalg.norm(tris[:, None, :, :] - centres[None, :, None, :], axis=3).max(axis=2)
        assign = d.argmin(axis=1)
        radii = np.array([d[assign == j, j].max() if np.any(assign == j) else 0.0 for j in range(k)])
        volume = float((radii**3).sum())
        if best is None or volume < best[0] - 1e-12:
            best = (volume, centres.copy(), radii.copy(), assign.copy())
        # move each centre towards the middle of its triangles' bounding box (minimax step)
        new = centres.copy()
        for j in range(k):
            pts = tris[assign == j].reshape(-1, 3)
            if len(pts):
                new[j] = 0.5 * (pts.min(axis=0) + pts.max(axis=0))
        if np.allclose(new, centres, atol=1e-7):
            break
        centres = 0.7 * centres + 0.3 * new
    _, centres, radii, _ = best
    # round centres to 1 mm, then recompute radii exactly for the rounded centres
    centres = np.round(centres, 3)
    d = np.linalg.norm(tris[:, None, :, :] - centres[None, :, None, :], axis=3).max(axis=2)
    assign = d.argmin(axis=1)
    radii = np.array([d[assign == j, j].max() if np.any(assign == j) else 0.0 for j in range(k)])
    radii = np.ceil((radii + MARGIN) * 1000.0) / 1000.0
    return centres, radii


def surface_samples(tris, per_tri=6, rng=None):
    """Vertices, edge midpoints, centroids and random barycentric points of every triangle."""
    a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
    pts = [a, b, c, (a + b) / 2, (b + c) / 2, (a + c) / 2, (a + b + c) / 3]
    for _ in range(per_tri):
        u, v = rng.random(len(tris)), rng.random(len(tris))
        flip = u + v > 1
        u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
        pts.append(a + (b - a) * u[:, None] + (c - a) * v[:, None])
    return np.concatenate(pts)


def slack(points, centres, radii):
    """radius − distance to the best sphere (≥ 0 means covered)."""
    d = np.linalg.norm(points[:, None, :] - centres[None, :, :], axis=2)
    return (radii[None, :] - d).max(axis=1)


def fk_fixture(path, rng):
    import pybullet as pb
    import pybullet_data

    cid = pb.connect(pb.DIRECT)
    robot = pb.loadURDF(os.path.join(pybullet_data.getDataPath(), "kuka_iiwa", "model.urdf"), useFixedBase=True)
    lim = np.radians([170, 120, 170, 120, 170, 120, 175])
    with open(path, "w") as f:
        f.write("# Link frames of the LBR iiwa 14 computed by Bullet (tools/fit_spheres.py).\n")
        f.write("# q1..q7 then, for links 1..7, x y z qw qx qy qz in the arm base frame\n")
        for _ in range(25):
            q = rng.uniform(-lim, lim)
            for j in range(7):
                pb.resetJointState(robot, j, q[j])
            row = list(q)
            for j in range(7):
                st = pb.getLinkState(robot, j, computeForwardKinematics=True)
                pos, orn = st[4], st[5]  # URDF link frame (not the inertial frame)
                row += list(pos) + [orn[3], orn[0], orn[1], orn[2]]
            f.write(",".join(f"{v:.12f}" for v in row) + "\n")
    pb.disconnect(cid)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--print-rust", action="store_true", help="print the sphere table as Rust")
    args = ap.parse_args()
    rng = np.random.default_rng(7)
    os.makedirs(OUT_DIR, exist_ok=True)
    rust, fixture = [], []
    worst = np.inf
    for link, k in enumerate(SPHERES_PER_LINK):
        tris = load_stl(os.path.join(mesh_dir(), f"link_{link}.stl"))
        centres, radii = fit(tris, k)
        dense = surface_samples(tris, per_tri=20, rng=rng)
        s = slack(dense, centres, radii)
        worst = min(worst, s.min())
        status = "ok" if s.min() >= 0 else "NOT COVERED"
        print(f"link {link}: {len(tris)} triangles, {k} spheres, radii {np.round(radii, 3)}, "
              f"{len(dense)} surface samples, min slack {s.min() * 1000:.2f} mm: {status}")
        for c, r in zip(centres, radii):
            rust.append(f"    ({link}, [{c[0]:.3f}, {c[1]:.3f}, {c[2]:.3f}], {r:.3f}),")
        # fixture: the 60 tightest points plus 240 random ones
        tight = dense[np.argsort(s)[:60]]
        rand = dense[rng.choice(len(dense), 240, replace=False)]
        for p in np.concatenate([tight, rand]):
            fixture.append(f"{link},{p[0]:.6f},{p[1]:.6f},{p[2]:.6f}")
    with open(os.path.join(OUT_DIR, "iiwa14_mesh_points.csv"), "w") as f:
        f.write("# Surface points of the pybullet iiwa 14 STL meshes in their link frames\n")
        f.write("# (tools/fit_spheres.py): link,x,y,z; the tightest 60 per link come first\n")
        f.write("\n".join(fixture) + "\n")
    fk_fixture(os.path.join(OUT_DIR, "iiwa14_fk_pybullet.csv"), rng)
    if args.print_rust:
        print("\n".join(rust))
    if worst < 0:
        sys.exit("coverage check failed")
    print("all link surfaces covered")


if __name__ == "__main__":
    main()
