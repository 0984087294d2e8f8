"""The fold of ``bench_cloth_fold.py`` stepped by a peer: Newton's VBD solver with self-contact, on Warp's CPU.

The same sheet as ours: its particles, masses and velocities, its springs (structural, shear and flexion,
with their stiffnesses and rest lengths), its triangles (for contact only: no membrane or bending
stiffness of their own), the floor at z = 0 with friction 0.3, the step h = 10 ms in 10 substeps, and
self-contact at our thickness (half the grid spacing), ``--newton-iterations`` VBD iterations per substep
(default 4: with one, the 64^2 sheet stretched 26% in its first step and 134% by its eighth). Our air
damping (0.2 /s) has no counterpart there. Crossings are counted by our exact test on the positions
after every step, strains by our measure. ``pip install newton`` (the ``[bench]`` extra) installs Newton and Warp; without them
:func:`newton_rows` stops with what to install.

References
----------
.. [1] A. H. Chen, Z. Liu, Y. Yang and C. Yuksel, "Vertex block descent", ACM Transactions on
   Graphics 43(4), 2024.
"""

import time

import numpy as np

from particles.collisions import TriangleMesh, intersections

SUBSTEPS = 10
FRICTION = 0.3


def _import():
    """Newton and Warp, or SystemExit saying what is missing."""
    try:
        import newton  # noqa: PLC0415
        import warp as wp  # noqa: PLC0415
    except ImportError as error:
        raise SystemExit(f"--peer newton needs Newton and Warp (pip install newton, or pip install "
                         f"'particles[bench]'): {error}") from None
    return newton, wp


def build(c, n, thickness, iterations=1):
    """Newton's model, solver, states and collision pipeline for our sheet `c` (n x n) on the floor."""
    newton, wp = _import()
    wp.config.quiet = True
    wp.set_device("cpu")
    builder = newton.ModelBuilder(up_axis=newton.Axis.Z, gravity=(0.0, 0.0, -9.81))
    ground = builder.default_shape_cfg.copy()
    ground.mu = FRICTION
    builder.add_ground_plane(cfg=ground)
    x, v = np.asarray(c.X[:, 0], dtype=float), np.asarray(c.X[:, 1], dtype=float)
    builder.add_particles([wp.vec3(*p) for p in x], [wp.vec3(*u) for u in v], [float(m) for m in c.m],
                          radius=[0.5 * thickness] * c.n)
    faces = TriangleMesh.grid(n, n).faces
    builder.add_triangles(faces[:, 0], faces[:, 1], faces[:, 2], tri_ke=[0.0] * len(faces),
                          tri_ka=[0.0] * len(faces), tri_kd=[0.0] * len(faces))
    edges = _edges(faces)
    builder.add_edges(*[list(map(int, e)) for e in edges.T], edge_ke=[0.0] * len(edges), edge_kd=[0.0] * len(edges))
    for s in c.springs.values():  # a loop over the three spring kinds
        for (i, j), k in zip(s.indices, s.k):  # a loop over springs: Newton's builder takes them one by one
            builder.add_spring(int(i), int(j), float(k), 0.0, 0.0)
    builder.color(include_bending=False)
    model = builder.finalize(device="cpu")
    model.spring_rest_length.assign(np.concatenate([s.rest_length for s in c.springs.values()]).astype(np.float32))
    model.soft_contact_mu = FRICTION
    model.soft_contact_margin = thickness
    solver = newton.solvers.SolverVBD(model, iterations=iterations, particle_enable_self_contact=True,
                                      particle_self_contact_margin=thickness,
                                      particle_self_contact_gap=0.5 * thickness)
    pipeline = newton.CollisionPipeline(model)
    return model, solver, pipeline


def _edges(faces):
    """Each edge of the mesh once with its two opposite vertices: rows (o1, o2, v1, v2), -1 on the border."""
    rows = {}
    for f in faces:  # a loop over faces (bench set-up only)
        for a in range(3):  # a loop over the face's three edges
            v1, v2, o = int(f[a]), int(f[(a + 1) % 3]), int(f[(a + 2) % 3])
            key = (min(v1, v2), max(v1, v2))
            if key in rows:
                rows[key][1] = o
            else:
                rows[key] = [o, -1, v1, v2]
    return np.array(list(rows.values()), dtype=int)


def _warm_up(c, iterations):
    """Compile (or load from Warp's cache) Newton's kernels: one substep of a 4 x 4 sheet of the same kind."""
    from bench_cloth_fold import upright_sheet  # noqa: PLC0415

    small = upright_sheet(4)
    model, solver, pipeline = build(small, 4, 0.5 / 3, iterations)
    state0, state1, control = model.state(), model.state(), model.control()
    contacts = pipeline.contacts()
    pipeline.collide(state0, contacts)
    solver.step(state0, state1, control, contacts, 1e-3)


def newton_rows(c, n, seconds, h, strains, iterations=1):
    """Step our sheet `c` with Newton's VBD; rows as bench_cloth_fold.run's: (t, wall, crossing pairs,
    None, structural, shear, flexion strains)."""
    _, wp = _import()
    _warm_up(c, iterations)
    thickness = 0.5 / (n - 1)
    model, solver, pipeline = build(c, n, thickness, iterations)
    state0, state1, control = model.state(), model.state(), model.control()
    contacts = pipeline.contacts()
    faces = TriangleMesh.grid(n, n).faces
    rows, t, dt = [], 0.0, h / SUBSTEPS
    for _ in range(round(seconds / h)):  # a loop over steps
        start = time.perf_counter()
        for _ in range(SUBSTEPS):  # a loop over substeps
            state0.clear_forces()
            pipeline.collide(state0, contacts)
            solver.step(state0, state1, control, contacts, dt)
            state0, state1 = state1, state0
        wp.synchronize()
        wall = time.perf_counter() - start
        t += h
        x = state0.particle_q.numpy().astype(float)
        rows.append((t, wall, len(intersections(x, faces)), None, *strains(c, x)))
    return rows
