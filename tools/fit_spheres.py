#!/usr/bin/env python3
"""Dev-only: fit and verify conservative collision spheres for the LBR iiwa 14 R820.

Reads the STL link meshes that the `pybullet` PyPI package ships
(`pybullet_data/kuka_iiwa/meshes/link_{0..7}.stl`, link frames = URDF link frames) and

1. fits K spheres per link that contain every triangle of the link (each triangle, split until
   no edge exceeds 10 mm, lies in one sphere with all three vertices; a sphere is convex, so
   the whole mesh surface is inside the union, not only the vertices) and overhang the arm as
   little as the count allows. Overhang is measured outside the link's body: the link's solid,
   the points its neighbours occupy at every angle of the joint between them (a joint housing
   turns inside its neighbour's flange), and, for link 0, the platform deck. A greedy cover
   picks, for the smallest bound T found by bisection, spheres whose surface stays within T
   of that body (an exact distance transform on a 4 mm grid), then shrinks each radius to the
   triangles it is left with, plus a margin;
2. verifies the coverage independently on dense samples of every triangle;
3. reports per link the overhang of the committed model (`shared/src/robot.rs`) and of the new
   fit, three ways: beyond the link's own mesh, beyond its body (the fit's measure), and
   beyond the posed arm at the 25 configurations of the FK fixture;
4. writes the committed fixture `shared/tests/data/iiwa14_mesh_points.csv` (a subsample of
   surface points, the tightest ones included) that the Rust test `spheres_cover_meshes` checks
   against the built-in model, and
5. writes `shared/tests/data/iiwa14_fk_pybullet.csv`: link frames computed by Bullet for random
   configurations, the independent FK reference of the Rust test `fk_matches_pybullet`.

Usage: pip install numpy scipy pybullet && python3 tools/fit_spheres.py [--print-rust] [--print-json]
Nothing in the product calls this script; its results are committed.
"""
import argparse
import os
import re
import struct
import sys

import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

# Spheres per link (link 0 = arm base flange, ... link 7 = last link); with the gripper's six,
# 42 of the model's 48.
SPHERES_PER_LINK = [3, 5, 5, 5, 5, 5, 4, 4]
MARGIN = 0.002  # m, added to every radius; also absorbs rounding to 1 mm
EDGE = 0.010  # m, triangles are split until no edge is longer
GRID = 0.004  # m, the distance transform's grid
SOLID_GRID = 0.003  # m, the inside grids of the link solids
CANDIDATES = 3000  # sphere centres tried per link (random points inside the link)
RADII = np.arange(0.020, 0.170, 0.004)  # m, sphere radii tried at every centre
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT_DIR = os.path.join(ROOT, "shared", "tests", "data")
ROBOT_RS = os.path.join(ROOT, "shared", "src", "robot.rs")

# URDF joint origins (xyz, rpy) of joints 1..7 and their limits, as in shared/src/robot.rs.
_H = np.pi / 2
JOINTS = [([0, 0, 0.1575], [0, 0, 0]), ([0, 0, 0.2025], [_H, 0, np.pi]),
          ([0, 0.2045, 0], [_H, 0, np.pi]), ([0, 0, 0.2155], [_H, 0, 0]),
          ([0, 0.1845, 0], [-_H, np.pi, 0]), ([0, 0, 0.2155], [_H, 0, 0]),
          ([0, 0.081, 0], [-_H, np.pi, 0])]
LIMITS = np.radians([170, 120, 170, 120, 170, 120, 175])
# The platform deck under link 0 (link-0 frame): the box the arm is mounted on.
DECK_LO, DECK_HI = np.array([-0.87, -0.315, -0.70]), np.array([0.21, 0.315, 0.0])


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


def split(tris, edge):
    """Bisects the longest edge of every triangle until no edge is longer than `edge`."""
    done = []
    while len(tris):
        e = np.linalg.norm(tris[:, [1, 2, 0]] - tris, axis=2)
        big = e.max(axis=1) > edge
        done.append(tris[~big])
        tris, e = tris[big], e[big]
        i, rows = e.argmax(axis=1), np.arange(len(tris))
        a, b, c = tris[rows, i], tris[rows, (i + 1) % 3], tris[rows, (i + 2) % 3]
        m = 0.5 * (a + b)
        tris = np.concatenate([np.stack([a, m, c], 1), np.stack([m, b, c], 1)])
    return np.concatenate(done)


class Solid:
    """The inside of a closed mesh on a grid: parity of the crossings of vertical rays."""

    def __init__(self, tris, h=SOLID_GRID):
        v = tris.reshape(-1, 3)
        self.h, self.lo = h, v.min(axis=0) - h
        self.n = np.ceil((v.max(axis=0) + h - self.lo) / h).astype(int) + 1
        axes = [self.lo[i] + h * np.arange(self.n[i]) for i in range(3)]
        x, y = np.meshgrid(axes[0], axes[1], indexing="ij")
        columns = np.stack([x.ravel(), y.ravel()], 1)
        a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
        den = (b[:, 1] - c[:, 1]) * (a[:, 0] - c[:, 0]) + (c[:, 0] - b[:, 0]) * (a[:, 1] - c[:, 1])
        ok = np.abs(den) > 1e-14
        a, b, c, den = a[ok], b[ok], c[ok], den[ok]
        self.grid = np.zeros(self.n, bool)
        for s in range(0, len(columns), 256):
            px, py = columns[s:s + 256, None, 0], columns[s:s + 256, None, 1]
            l1 = ((b[:, 1] - c[:, 1]) * (px - c[:, 0]) + (c[:, 0] - b[:, 0]) * (py - c[:, 1])) / den
            l2 = ((c[:, 1] - a[:, 1]) * (px - c[:, 0]) + (a[:, 0] - c[:, 0]) * (py - c[:, 1])) / den
            l3 = 1 - l1 - l2
            hit = (l1 >= 0) & (l2 >= 0) & (l3 >= 0)
            z = l1 * a[:, 2] + l2 * b[:, 2] + l3 * c[:, 2]
            for k in range(len(hit)):
                crossings = np.sort(z[k][hit[k]])
                i = s + k
                self.grid[i // self.n[1], i % self.n[1]] = np.searchsorted(crossings, axes[2]) % 2 == 1

    def contains(self, p):
        idx = np.round((p - self.lo) / self.h).astype(int)
        ok = np.all((idx >= 0) & (idx < self.n), axis=1)
        out = np.zeros(len(p), bool)
        i = idx[ok]
        out[ok] = self.grid[i[:, 0], i[:, 1], i[:, 2]]
        return out


def joint_origin(j):
    """(R, t) of joint j+1's origin in the frame of link j."""
    xyz, rpy = JOINTS[j]
    return Rotation.from_euler("xyz", rpy).as_matrix(), np.array(xyz, float)


def rot_z(t):
    c, s = np.cos(t), np.sin(t)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def in_body(link, p, solids, angles=24):
    """Points `p` (link frame) inside the link's body: its solid, the points each neighbour
    occupies at every sampled angle of the joint between them, and (link 0) the deck."""
    inside = solids[link].contains(p)
    if link < 7:  # link+1 hangs on joint link+1: x_{l+1} = Rz(θ)ᵀ Rᵀ (x − t)
        r, t = joint_origin(link)
        core = np.ones(len(p), bool)
        for th in np.linspace(-LIMITS[link], LIMITS[link], angles):
            core &= solids[link + 1].contains((p - t) @ (r @ rot_z(th)))
        inside |= core
    if link > 0:  # link−1 carries joint link: x_{l−1} = R Rz(θ) x + t
        r, t = joint_origin(link - 1)
        core = np.ones(len(p), bool)
        for th in np.linspace(-LIMITS[link - 1], LIMITS[link - 1], angles):
            core &= solids[link - 1].contains(p @ (r @ rot_z(th)).T + t)
        inside |= core
    else:
        inside |= np.all((p >= DECK_LO) & (p <= DECK_HI), axis=1)
    return inside


class BodyDistance:
    """Distance from a point (link frame) to the link's body; 0 inside (grid lookup)."""

    def __init__(self, link, tris, solids, pad=0.16):
        v = tris.reshape(-1, 3)
        self.lo = v.min(axis=0) - pad
        self.n = np.ceil((v.max(axis=0) + pad - self.lo) / GRID).astype(int) + 1
        axes = [self.lo[i] + GRID * np.arange(self.n[i]) for i in range(3)]
        g = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
        inside = in_body(link, g, solids).reshape(self.n)
        self.d = ndimage.distance_transform_edt(~inside) * GRID

    def __call__(self, p):
        idx = np.clip(np.round((p - self.lo) / GRID).astype(int), 0, self.n - 1)
        return self.d[idx[..., 0], idx[..., 1], idx[..., 2]]


def fibonacci_sphere(n):
    i = np.arange(n) + 0.5
    phi, th = np.arccos(1 - 2 * i / n), np.pi * (1 + 5 ** 0.5) * i
    return np.stack([np.cos(th) * np.sin(phi), np.sin(th) * np.sin(phi), np.cos(phi)], 1)


def farthest_vertex(tris, centres):
    """(n_tri, n_centre): distance from each centre to the farthest vertex of each triangle."""
    out = np.empty((len(tris), len(centres)), np.float32)
    for s in range(0, len(tris), 2000):
        out[s:s + 2000] = np.linalg.norm(tris[s:s + 2000, :, None, :] - centres[None, None], axis=3).max(axis=1)
    return out


def greedy_cover(covers, k):
    """Indices of at most k columns of `covers` (triangle × sphere) covering every row, or None."""
    open_ = np.ones(len(covers), bool)
    chosen = []
    while open_.any():
        gain = covers[open_].sum(axis=0)
        j = int(gain.argmax())
        if len(chosen) == k or gain[j] == 0:
            return None
        chosen.append(j)
        open_ &= ~covers[:, j]
    return chosen


def fit(link, tris, k, distance, solids, rng):
    """k spheres containing every triangle of the link, overhanging its body (`distance`, a
    BodyDistance) as little as the greedy cover finds (see the module documentation); returns
    centres, radii and the bound T."""
    small = split(tris, EDGE)
    v = tris.reshape(-1, 3)
    pts = rng.uniform(v.min(axis=0), v.max(axis=0), size=(4 * CANDIDATES, 3))
    centres = pts[solids[link].contains(pts)][:CANDIDATES]
    surface = fibonacci_sphere(300)
    # overhang[c, r]: the farthest a sphere (centre c, radius RADII[r]) reaches beyond the body,
    # made non-decreasing in r so that "radius allowed under T" is a prefix.
    overhang = np.stack([distance(centres[:, None, :] + r * surface[None]).max(axis=1) for r in RADII], 1)
    overhang = np.maximum.accumulate(overhang, axis=1)
    reach = farthest_vertex(small, centres)

    def allowed(t):
        n = (overhang <= t).sum(axis=1)
        return np.where(n > 0, RADII[np.maximum(n - 1, 0)], 0.0)

    lo, hi, best = 0.0, 0.15, None
    for _ in range(14):
        t = 0.5 * (lo + hi)
        chosen = greedy_cover(reach <= (allowed(t) - MARGIN)[None, :], k)
        if chosen is None:
            lo = t
        else:
            hi, best = t, (t, chosen)
    t, chosen = best
    c = np.round(centres[chosen], 3) + 0.0  # + 0.0: no "-0.000"
    d = np.linalg.norm(small[:, :, None, :] - c[None, None], axis=3).max(axis=1)
    owner = (d - allowed(t)[chosen][None]).argmin(axis=1)
    r = np.array([d[owner == j, j].max() if np.any(owner == j) else 0.0 for j in range(len(c))])
    keep = r > 0
    return c[keep], np.ceil((r[keep] + MARGIN) * 1000.0) / 1000.0, t


def point_mesh_distance(points, tris):
    """Exact distance from each point to the nearest triangle (closest-point regions)."""
    a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
    best = np.full(len(points), np.inf)
    for s in range(0, len(points), 256):
        p = points[s:s + 256, None, :]

        def to_segment(x0, x1):
            d = x1 - x0
            t = np.clip(((p - x0) * d).sum(-1) / np.maximum((d * d).sum(-1), 1e-300), 0, 1)
            return np.linalg.norm(p - (x0 + d * t[..., None]), axis=-1)

        n = np.cross(b - a, c - a)
        nn = np.maximum((n * n).sum(-1), 1e-300)
        h = ((p - a) * n).sum(-1) / nn
        q = p - n * h[..., None]  # projection onto the triangle's plane
        inside = np.ones(q.shape[:2], bool)
        for x0, x1 in ((a, b), (b, c), (c, a)):
            inside &= (np.cross(x1 - x0, q - x0) * n).sum(-1) >= 0
        edge = np.minimum(np.minimum(to_segment(a, b), to_segment(b, c)), to_segment(c, a))
        d = np.where(inside, np.abs(h) * np.sqrt(nn), edge)
        best[s:s + 256] = d.min(axis=1)
    return best


def union_surface(centres, radii, n=400):
    """Samples of the union's surface: sphere surface points inside no other sphere."""
    u = fibonacci_sphere(n)
    out = []
    for c, r in zip(centres, radii):
        p = c + r * u
        d = np.linalg.norm(p[:, None, :] - centres[None], axis=2)
        out.append(p[~np.any(d < radii[None] - 1e-9, axis=1)])
    return np.concatenate(out)


def own_overhang(tris, centres, radii, solid):
    """Farthest the union reaches beyond the link's own mesh (points inside it count 0)."""
    p = union_surface(centres, radii)
    p = p[~solid.contains(p)]
    return point_mesh_distance(p, tris).max() if len(p) else 0.0


def body_overhang(distance, centres, radii):
    """Farthest the union reaches beyond the link's body (the fit's measure)."""
    return distance(union_surface(centres, radii)).max()


def fk_frames(path):
    """Per configuration of the FK fixture: (R, t) of links 0..7 in the arm base frame."""
    out = []
    for line in open(path):
        if line.startswith("#"):
            continue
        v = np.array([float(x) for x in line.split(",")])
        frames = [(np.eye(3), np.zeros(3))]
        for j in range(7):
            x = v[7 + 7 * j: 14 + 7 * j]
            frames.append((Rotation.from_quat([x[4], x[5], x[6], x[3]]).as_matrix(), x[:3]))
        out.append(frames)
    return out


def arm_overhang(model, meshes, solids, configurations, rng):
    """Per link: farthest its union reaches beyond the posed arm (every link's solid and the
    deck), over the FK fixture's configurations; distances to dense surface samples."""
    samples = [surface_samples(t, per_tri=30, rng=rng) for t in meshes]
    worst = np.zeros(len(model))
    for frames in configurations:
        world = lambda link, p: p @ frames[link][0].T + frames[link][1]
        tree = cKDTree(np.concatenate([world(j, s) for j, s in enumerate(samples)]))
        for link, (c, r) in enumerate(model):
            p = world(link, union_surface(c, r))
            d, _ = tree.query(p)
            body = np.all((p >= DECK_LO) & (p <= DECK_HI), axis=1)
            for j, solid in enumerate(solids):
                body |= solid.contains((p - frames[j][1]) @ frames[j][0])
            worst[link] = max(worst[link], np.where(body, 0.0, d).max())
    return worst


def committed_model():
    """The link spheres of `shared/src/robot.rs` (links 0..7) as [(centres, radii)]."""
    src = open(ROBOT_RS).read()
    table = src[src.index("const IIWA14_SPHERES"):]
    rows = re.findall(r"\((\d), \[([-\d.]+), ([-\d.]+), ([-\d.]+)\], ([\d.]+)\)", table)
    rows = np.array([[float(x) for x in row] for row in rows])
    return [(rows[rows[:, 0] == link, 1:4], rows[rows[:, 0] == link, 4]) for link in range(8)]


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
    ap.add_argument("--print-json", action="store_true", help="print the spheres as prf-spheres JSON entries")
    ap.add_argument("--fk-fixture", action="store_true", help="also rewrite the Bullet FK fixture")
    args = ap.parse_args()
    rng = np.random.default_rng(7)
    os.makedirs(OUT_DIR, exist_ok=True)
    meshes = [load_stl(os.path.join(mesh_dir(), f"link_{link}.stl")) for link in range(8)]
    solids = [Solid(t) for t in meshes]
    before = committed_model()
    model, rust, json, fixture = [], [], [], []
    worst = np.inf
    print("overhang, mm: beyond the link's own mesh | beyond its body (the fit's measure)")
    for link, k in enumerate(SPHERES_PER_LINK):
        tris = meshes[link]
        distance = BodyDistance(link, tris, solids)
        centres, radii, bound = fit(link, tris, k, distance, solids, rng)
        model.append((centres, radii))
        dense = surface_samples(tris, per_tri=20, rng=rng)
        s = slack(dense, centres, radii)
        worst = min(worst, s.min())
        old_c, old_r = before[link]
        print(f"link {link}: {len(tris)} triangles, {len(radii)} spheres, radii {np.round(radii, 3)}, "
              f"{len(dense)} surface samples, min slack {s.min() * 1000:.2f} mm: "
              f"{'ok' if s.min() >= 0 else 'NOT COVERED'}; bound T {bound * 1000:.1f}\n"
              f"  committed ({len(old_r)} spheres) "
              f"{own_overhang(tris, old_c, old_r, solids[link]) * 1000:5.1f} | "
              f"{body_overhang(distance, old_c, old_r) * 1000:5.1f}   new "
              f"{own_overhang(tris, centres, radii, solids[link]) * 1000:5.1f} | "
              f"{body_overhang(distance, centres, radii) * 1000:5.1f}", flush=True)
        for c, r in zip(centres, radii):
            rust.append(f"    ({link}, [{c[0]:.3f}, {c[1]:.3f}, {c[2]:.3f}], {r:.3f}),")
            json.append(f'    {{ "link": "iiwa_link_{link}", "centre": [{c[0]:.3f}, {c[1]:.3f}, {c[2]:.3f}], '
                        f'"radius": {r:.3f} }},')
        # fixture: the 60 tightest points plus 240 random ones
        tight = dense[np.argsort(s)[:60]]
        rand = dense[rng.choice(len(dense), 240, replace=False)]
        for p in np.concatenate([tight, rand]):
            fixture.append(f"{link},{p[0]:.6f},{p[1]:.6f},{p[2]:.6f}")
    fk_path = os.path.join(OUT_DIR, "iiwa14_fk_pybullet.csv")
    configurations = fk_frames(fk_path)
    for name, m in (("committed", before), ("new", model)):
        arm = arm_overhang(m, meshes, solids, configurations, np.random.default_rng(11))
        print(f"beyond the posed arm ({len(configurations)} configurations), {name}, mm: {np.round(arm * 1000, 1)}")
    with open(os.path.join(OUT_DIR, "iiwa14_mesh_points.csv"), "w") as f:
        f.write("# Surface points of the pybullet iiwa 14 STL meshes in their link frames\n")
        f.write("# (tools/fit_spheres.py): link,x,y,z; the tightest 60 per link come first\n")
        f.write("\n".join(fixture) + "\n")
    if args.fk_fixture:
        fk_fixture(fk_path, np.random.default_rng(8))
    if args.print_rust:
        print("\n".join(rust))
    if args.print_json:
        print("\n".join(json))
    if worst < 0:
        sys.exit("coverage check failed")
    print("all link surfaces covered")


if __name__ == "__main__":
    main()
