"""Cloth collisions: cost per step against the number of triangles, and the intersection test's own cost.

Part 2 measures the same physical scene at every resolution: a 1 m square
sheet of n^2 particles folded over along its rows (the lower layer on a
table, a loop of radius 6 cm, a ramp of 20 cm, and the rest of the sheet
lying back over the lower layer), with the thickness proportional to the
spacing, ``0.25 dx``, and the gaps proportional to the thickness (the lower
layer one thickness above the table, the upper layer 0.95 thickness above
the lower: pressed into contact, its rows halfway between the lower
layer's at every n). Then the contacts per triangle do not change with n
(printed), and a linear method costs the same per triangle. (With the fold
drawn in grid spacings instead, a tighter loop at every n, and the layers'
rows registered differently at each n, the proximity impulses per triangle
grew from 0.85 at 32^2 to 2.38 at 128^2 and the fitted slope was 1.20.)

Part 1. ``intersections(x, mesh)`` (the exact test, O(m) on the bucket grid
of boxes) on a sheet whose second half is folded back *through* the first
(the pairs found are checked against the known answer, 3 (n - 1)), against
the O(m^2) all-pairs box test that the grid replaces (vectorized, in
blocks).

Part 2. One step of ``ClothCollisions`` (proximity, continuous tests,
impact zones) around symplectic Euler at 90% of its stable step, after
``warmup`` steps in contact: the time of the inner step alone and of the
whole step, the collision fix's share, each per triangle, the pairs closer
than the thickness per triangle (``ClothCollisions.pairs_closer_than``, the
contacts the step handles), and the invariant checked on the state (the time of
``intersections`` and the pairs it finds: 0); the fitted log-log slopes of
the whole step's and of the fix's time against the number of triangles
(1 = linear).

Run:  python bench/bench_cloth_collisions.py [--quick]
"""

import argparse
import os
import sys
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _timing import best_time  # noqa: E402

from particles.collisions import box_pairs, intersections  # noqa: E402
from particles.integrators import symplectic_euler  # noqa: E402
from particles.massspring import cloth  # noqa: E402
from particles.collisions import TriangleMesh  # noqa: E402
from particles.collisions import Plane  # noqa: E402


def folded(n, gap, z0=0.0, radius=0.06, ramp=0.2):
    """Positions of an n x n, 1 m sheet folded over along its rows, the upper layer `gap` above the lower.

    The rows follow a curve in the (y, z) plane, at their arc lengths (so that
    the springs keep about their rest lengths): the lower layer at ``z0``, a
    half loop of `radius`, a ramp down of length `ramp` (both in metres, the
    same at every n), and the rest of the upper layer lying ``gap`` above the
    lower one, its rows halfway between the lower layer's.
    """
    dx, r = 1.0 / (n - 1), radius
    drop = 2 * r - gap
    run = np.sqrt(ramp**2 - drop**2)
    a = (1.0 - np.pi * r) / 2  # length of the lower layer, made a little longer below
    # Upper row j lies at y = 2 a + pi r + ramp - run - j dx: lengthen the lower layer by less than dx / 2 so
    # that the upper rows fall halfway between the lower ones at every n (the same registration of the layers).
    a += np.mod(0.5 * dx - (2 * a + np.pi * r + ramp - run), dx) / 2
    phi = np.linspace(0.0, np.pi, 200)
    u = np.linspace(0.0, 1.0, 50)
    y = np.concatenate([[0.0], a + r * np.sin(phi), a - u * run, [a - run - 1.0]])
    z = np.concatenate([[z0], z0 + r - r * np.cos(phi), z0 + 2 * r - u * drop, [z0 + gap]])
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(y), np.diff(z)))])
    s = np.linspace(0.0, 1.0, n)  # arc length of each row
    i, j = np.meshgrid(np.arange(n), np.arange(n))  # vertex j n + i
    return np.stack([s[i], np.interp(s, arc, y)[j], np.interp(s, arc, z)[j]], axis=-1).reshape(-1, 3)


def all_box_pairs(lo, hi, block=512):
    """The O(m^2) baseline: every pair of boxes tested, in blocks of rows."""
    found = []
    for a in range(0, len(lo), block):  # a loop over blocks of boxes
        over = np.all((lo[a:a + block, None] <= hi[None]) & (lo[None] <= hi[a:a + block, None]), axis=2)
        i, j = np.nonzero(over)
        keep = i + a < j
        found.append((i[keep] + a, j[keep]))
    return np.concatenate([f[0] for f in found]), np.concatenate([f[1] for f in found])


def fitted_slope(m, t):
    return np.polyfit(np.log(m), np.log(t), 1)[0]


def folded_through(n):
    """An n x n sheet (spacing 1/(n-1)) lying flat for its first rows, the rest folded back through them.

    Rows ``j <= J`` lie at z = 0; row ``J + k`` lies on a plane that comes back
    over the flat part and cuts it along a line (at ``k = k*``, a third of the
    way between two rows of the fold, a sixth of the way between two rows of
    the flat part), so that exactly 3 pairs of triangles cross per column of
    cells: ``3 (n - 1)`` in all.
    """
    J = n // 2
    rows = n - J - 1
    k_star = rows // 2 + 1 / 3
    k = np.arange(1, rows + 1)
    y = np.concatenate([np.arange(J + 1), J + 0.5 - k])
    z = np.concatenate([np.zeros(J + 1), 1.0 - k / k_star])
    i, j = np.meshgrid(np.arange(n), np.arange(n))
    return np.stack([i, y[j], z[j]], axis=-1).reshape(-1, 3).astype(float) / (n - 1)


def part1(sizes, baseline_up_to):
    print("Part 1: intersections(x, mesh) on a sheet folded through itself (ms per call)")
    print(f"{'particles':>10} {'triangles':>10} {'crossing':>9} {'3 (n-1)':>8} {'boxes met':>10} "
          f"{'exact test':>11} {'all box pairs':>14} {'ratio':>7}")
    ms, ts = [], []
    for n in sizes:
        mesh = TriangleMesh.grid(n, n)
        x = folded_through(n)
        found = intersections(x, mesh)
        assert len(found) == 3 * (n - 1), (n, len(found))
        T = x[mesh.faces]
        lo, hi = T.min(axis=1), T.max(axis=1)
        met = len(box_pairs(lo, hi)[0])
        t_exact = best_time(lambda: intersections(x, mesh), repeat=3)
        if n <= baseline_up_to:
            t_all = best_time(lambda: all_box_pairs(lo, hi), repeat=1, min_time=0.0)
            assert len(all_box_pairs(lo, hi)[0]) == met
            extra = f"{1e3 * t_all:>14.1f} {t_all / t_exact:>6.0f}x"
        else:
            extra = f"{'-':>14} {'-':>7}"
        print(f"{n:>7}^2 {mesh.m:>10} {len(found):>9} {3 * (n - 1):>8} {met:>10} {1e3 * t_exact:>11.1f} {extra}")
        ms.append(mesh.m)
        ts.append(t_exact)
    print(f"fitted slope of the exact test's time against the triangles: {fitted_slope(ms, ts):.2f}")


def sheet_in_contact(n, warmup=10):
    """The folded sheet pressed onto itself and onto a table, after `warmup` steps, with its collision fix.

    The same physical scene at every n: the fold's loop and ramp in metres,
    the thickness ``0.25 dx``, the gaps in thicknesses.
    """
    from particles.collisions import ClothCollisions

    dx = 1.0 / (n - 1)
    thickness = 0.25 * dx
    c = cloth(n, n, width=1.0, height=1.0, plane="horizontal", origin=(0.0, 0.0, thickness), pins=None,
              scaling="physical", stretch_modulus=200.0, damping=0.5)
    mesh = TriangleMesh.grid(n, n)
    table = Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0])
    guard = ClothCollisions.from_system(c, mesh, thickness, friction=0.3, bodies=[table])  # rest: flat
    X = c.X.copy()
    X[:, 0] = folded(n, 0.95 * thickness, z0=thickness)  # the layers pressed together
    c.set_state(X)
    h = 0.9 * c.max_stable_step()
    step = guard.stepper(symplectic_euler)
    c.run(warmup * h, h, method=step, every=warmup)
    return c, mesh, guard, step, h


def contacts(result):
    """The counts of a ClothCollisions step, compactly."""
    names = ("proximity", "ccd", "zones", "zone_vertices", "body_vertices")
    return ", ".join(f"{name} {getattr(result, name)}" for name in names if hasattr(result, name))


def part2(sizes):
    print("\nPart 2: one step of ClothCollisions around symplectic Euler, the same folded sheet on a table at "
          "every n (ms; per triangle in us)")
    print(f"{'particles':>10} {'triangles':>10} {'h (ms)':>7} {'inner':>7} {'whole step':>11} {'/ tri':>6} "
          f"{'fix':>8} {'/ tri':>6} {'close / tri':>11} {'invariant':>9} {'pairs':>6}  last step")
    ms, wholes, fixes, pairs = [], [], [], []
    for n in sizes:
        c, mesh, guard, step, h = sheet_in_contact(n)
        X, t = c.X.copy(), c.t
        t_inner = best_time(lambda: symplectic_euler(c.derivative, X, t, h), repeat=5)
        t_whole = best_time(lambda: step(c.derivative, X, t, h), repeat=3)
        fix = max(t_whole - t_inner, 1e-9)
        ms.append(mesh.m)
        wholes.append(t_whole)
        fixes.append(fix)
        pairs.append(len(guard.pairs_closer_than(X[:, 0])))  # vertex-face and edge-edge pairs within thickness
        t_check = best_time(lambda: intersections(X[:, 0], mesh), repeat=3)
        crossing = len(intersections(X[:, 0], mesh))
        print(f"{n:>7}^2 {mesh.m:>10} {1e3 * h:>7.3f} {1e3 * t_inner:>7.2f} {1e3 * t_whole:>11.1f} "
              f"{1e6 * t_whole / mesh.m:>6.1f} {1e3 * fix:>8.1f} {1e6 * fix / mesh.m:>6.1f} "
              f"{pairs[-1] / mesh.m:>11.2f} {1e3 * t_check:>9.1f} {crossing:>6}  {contacts(guard.last)}")
    print(f"fitted slope of the time per step against the triangles: {fitted_slope(ms, wholes):.2f} "
          f"(the fix alone: {fitted_slope(ms, fixes):.2f}; 1 = linear)")
    print(f"pairs closer than the thickness per triangle: {', '.join(f'{p / m:.2f}' for p, m in zip(pairs, ms))}")
    return ms, wholes


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="32^2 to 64^2 only")
    parser.add_argument("--part", choices=("1", "2", "both"), default="both")
    parser.add_argument("--sizes", type=int, nargs="+", help="particles per side (default 32 48 64 96 128)")
    args = parser.parse_args()
    sizes = args.sizes or ([32, 48, 64] if args.quick else [32, 48, 64, 96, 128])
    if args.part in ("1", "both"):
        part1(sizes, baseline_up_to=64)
    if args.part in ("2", "both"):
        part2(sizes)


if __name__ == "__main__":
    main()
