"""Cloth collisions as a triangle mesh: proximity, continuous detection and impact zones.

The particle self-collision of :mod:`particles.collisions.selfcollision` lets triangles
cross between particles, and lets a particle that moves more than a
thickness in one step pass through. Bridson, Fedkiw and Anderson [1]_ treat
the cloth as a triangle mesh and fix each step after the time integrator,
with the step's average velocity ``vbar = (x1 - x0) / h`` (the positions
move on straight lines ``x0 + t h vbar`` within the step):

1. **Bodies.** A free vertex that ends closer than ``thickness`` to a body
   (an implicit surface of :mod:`particles.collisions.surfaces`, or a moving one with
   ``.at(t)`` and ``.velocity(x, t)``) is moved out along the normal to
   ``H = thickness`` at ``t + h``; its ``vbar`` changes by that
   displacement over ``h`` (an inelastic normal response), and Coulomb
   friction then reduces its tangential velocity relative to the body's
   surface by at most ``friction`` times that change. Edges are sampled at
   ``1/4, 1/2, 3/4`` of their length; a sample closer than ``thickness / 2``
   (at a box's corner, over a thin bar) moves both ends out, weighted by
   inverse mass (Jacobi with averaging).
2. **Proximity.** Vertex-face and edge-edge pairs closer than ``thickness``
   at ``x0``, or that would end closer along their normal
   (``d + h v_N < thickness`` with ``v_N = n . sum_j w_j vbar_j``, the
   four-vertex form of :mod:`particles.collisions.proximity`), get a normal impulse
   that lets them approach down to ``thickness`` and no further, and pushes
   pairs already inside it apart by ``repulsion`` times their overlap per
   step (a bounded repulsion, after Bridson's spring bounded by the overlap).
   Coulomb friction reduces their relative tangential velocity by at most
   ``friction`` times the normal change. An impulse ``I`` along ``n`` changes
   ``vbar_j`` by ``w_j I n / m_j``: with ``sum_j w_j = 0`` the momentum of the
   cloth is kept exactly (a pinned vertex has ``1 / m = 0``), and since
   ``n`` is parallel to ``sum_j w_j x_j`` the angular momentum too. The pairs
   are solved together by Jacobi iterations (each followed by the bodies'
   vertex pass, so that a sheet resting on another on a floor is held by
   both); each impulse is divided by the largest load ``sum |w_j|`` of the
   active contacts at its free vertices (an average that keeps momentum;
   from the second iteration on, by that load over ``relaxation``, at least
   1, because what is still active then is a stack of conflicting layers,
   which plain averaging moves by one layer per iteration),
   or, with ``method="gauss-seidel"``, contacts go one vertex-disjoint
   colour group at a time. Pairs closer than ``rest_distance`` in the rest
   shape (neighbours on the same sheet) never repel, and an edge-edge pair
   whose closest point is an edge's end is left to the vertex-face pairs of
   that vertex (the same contact counted once less).
2b. **Strain limit** (optional, :mod:`particles.collisions.strain_limit`): the stretch springs longer
   than ``(1 + s) L0`` at ``x0 + h vbar`` are shortened by Provot's projection, alternating with the
   body stage; after stages 3 and 4, if a spring is too long again, the limit and both stages run again
   (at most ``strain_rounds`` times), so the step ends with the continuous test. Stages 3 and 4 ended
   with a motion free of contact, so the test that follows a limit starts with the pairs that hold a
   vertex the limit (or the bodies) moved: the others move as they did.
3. **Continuous detection** (:mod:`particles.collisions.ccd`) over ``x0 -> x0 + h vbar``:
   each colliding pair gets an inelastic impulse that stops its approach
   along the normal at the time of impact (and pushes it to
   ``separation`` if it started closer), in groups of contacts that share
   no vertex (a Gauss-Seidel sweep, :func:`particles.xpbd.colouring.color_constraints`).
   Detection is repeated on the pairs whose vertices moved, up to
   ``ccd_iterations`` times.
4. **Impact zones** (Provot [2]_, Bridson et al. [1]_), the fail-safe: the
   vertices of the collisions left are merged into zones (connected
   components of the graph of collisions, :func:`scipy.sparse.csgraph.connected_components`),
   and each zone moves rigidly with the linear and angular momentum of its
   vertices (``omega = I^-1 L`` about its centre of mass, the rotation applied
   exactly by Rodrigues' formula). A rigid motion keeps every orientation of
   the zone's own vertices, so it cannot collide with itself. A zone that
   holds a pinned vertex stays where it is; a vertex that an impulse pushed
   into a body (below ``thickness / 2``, or an edge sample below zero)
   moves with the body, and so does its zone. Detect again, merge, repeat
   until no collision is left (at most ``zone_iterations`` passes; if it
   still fails every free vertex keeps its start position, which was
   collision-free, and ``last.converged`` is False).
5. **End of step**: ``x1 = x0 + h vbar`` and ``v1`` changed by the same
   change of velocity as ``vbar``.

What it achieves, for a start of step without intersections: the step ends
only when the continuous test finds no vertex-face or edge-edge contact
during it, so no two triangles intersect at its end
(:func:`particles.collisions.triangle_crossing.intersections`; checked after every step
of every test); every free vertex ends at ``H >= thickness / 2`` of every
body and every edge sample at ``H >= 0`` (the vertices normally at
``thickness``). The proximity stage keeps pairs about ``thickness`` apart,
not exactly: its iterations stop at ``tol``, closest points slide within
the step, and in dense, fast contact (a large sheet crumpling on a floor)
pairs come much closer before the repulsion separates them again; the
continuous test is what keeps them from crossing.

Limits: bodies are tested at the end of the step only (a vertex faster than
the body's size per step can pass through it); in-plane motion of coplanar
pairs is left to the proximity stage; the impact zones make the cloth
locally rigid when the other stages fail, which shows as stiff patches.

**Candidates** come from swept boxes in a bucket grid
(:func:`particles.collisions.triangle_crossing.box_pairs`) and are kept from step to step
as in a Verlet list: searched with boxes padded by ``thickness / 2`` plus a
skin of ``thickness / 2``, again only when a vertex leaves its box by more
than the skin (when only a few do, only their boxes grow and are tested
against every box, cheaper than a new grid). Boxes are compared in a frame that moves with the median
displacement (contacts depend on relative motion only), so a sheet falling
as a whole needs no new search.

**Composition.** :meth:`ClothCollisions.stepper` wraps any stepper or solver
(:mod:`particles.integrators.solvers`), as :meth:`particles.constraints.ProvotConstraint.stepper`
does; put it outermost, after Provot's projection, so that nothing moves
the cloth after its treatment::

    mesh = TriangleMesh.grid(nx, ny)
    cc = ClothCollisions.from_system(sheet, mesh, thickness=0.5 * dx, bodies=[floor], friction=0.3)
    step = cc.stepper(ProvotConstraint.from_system(sheet).stepper(symplectic_euler))
    sheet.run(1.0, h, method=step)

References
----------
.. [1] R. Bridson, R. Fedkiw and J. Anderson, "Robust treatment of collisions,
   contact and friction for cloth animation", ACM Transactions on Graphics
   21(3) (SIGGRAPH 2002), 594-603.
.. [2] X. Provot, "Collision and self-collision handling in cloth model
   dedicated to design garments", Graphics Interface 1997, 177-189.
"""

from dataclasses import dataclass

import numpy as np

from .._checks import as_float_array, count, mass_array, nonnegative_number, pinned_indices, positive_number
from ..backends import check_backend
from ..integrators.solvers import after
from ..constraints.colouring import color_constraints
from .bodies import BodyStage, StaticBody
from .candidate_cache import CandidateCache, compiled_stages
from .candidates import candidate_pairs
from .ccd import Impacts, detect_pairs
from .mesh import TriangleMesh
from .proximity import dot, edge_edge_kernel, vertex_face_kernel
from .proximity_impulses import ProximityStage
from .strain_limit import StrainLimitStage, strain_limit_from_system
from .surfaces import Surface
from .zones import ImpactZoneStage

__all__ = ["ClothCollisions", "ClothCollisionResult"]


@dataclass(frozen=True)
class ClothCollisionResult:
    """What one step of :meth:`ClothCollisions.resolve` did (counts).

    Attributes
    ----------
    body_vertices : int
        Vertices moved out of a body's thickness (stage 1).
    body_edges : int
        Edge samples moved out (stage 1).
    proximity : int
        Vertex-face and edge-edge pairs that received a proximity impulse.
    ccd : int
        Collisions found by the continuous test (all passes of stage 3).
    ccd_passes : int
        Detection passes of stage 3.
    zones : int
        Impact zones at the end of stage 4 (0 when stage 3 left no collision).
    zone_vertices : int
        Vertices in them.
    zone_passes : int
        Passes of stage 4.
    anchored : int
        Vertices held to a body in stage 4.
    converged : bool
        Whether the last detection found no collision (else every free vertex was stopped).
    strain_sweeps : int
        Gauss-Seidel sweeps of the strain limit (all its rounds).
    strain_rounds : int
        Continuous tests run after a strain limit (1 when the first held).
    max_strain : float
        Largest strain of the limited springs at the end of the step (0 without a limit).
    """

    body_vertices: int = 0
    body_edges: int = 0
    proximity: int = 0
    ccd: int = 0
    ccd_passes: int = 0
    zones: int = 0
    zone_vertices: int = 0
    zone_passes: int = 0
    anchored: int = 0
    converged: bool = True
    strain_sweeps: int = 0
    strain_rounds: int = 0
    max_strain: float = 0.0


class ClothCollisions(BodyStage, ProximityStage, StrainLimitStage, ImpactZoneStage):
    """Collisions of a cloth mesh with itself and with bodies, applied after each step.

    Parameters
    ----------
    mesh : TriangleMesh
        Faces over the ``n`` particles (the cloth's vertices).
    thickness : float
        Distance kept between the cloth's pieces, and between the cloth and
        bodies, in metres (> 0). About half the grid spacing: pairs closer
        than `rest_distance` at rest are neighbours and never repel.
    m : float or array_like, shape (n,)
        Masses, in kg (> 0).
    pinned : array_like of int or bool
        Vertices that never move (infinite mass).
    friction : float
        Coulomb coefficient between cloth pieces and with bodies (>= 0).
    bodies : sequence
        Implicit surfaces (:class:`particles.collisions.surfaces.Surface`, static) or
        moving bodies with ``at(t)`` (the surface at time ``t``) and
        ``velocity(x, t)`` (the velocity of the body's point at ``x``), e.g.
        :class:`particles.collisions.moving.MovingSurface`.
    ccd : bool
        Run the continuous test (stage 3).
    zones : bool
        Run the impact zones (stage 4; needs `ccd`).
    proximity : bool
        Run the proximity impulses (stage 2).
    iterations : int
        Iterations of the proximity stage (>= 1).
    ccd_iterations : int
        Detection and impulse passes of the continuous stage (>= 0; with 0,
        what is found goes to the impact zones at once).
    zone_iterations : int
        Largest number of passes of the impact zones (>= 1).
    x_rest : array_like, shape (n, 3), optional
        Rest positions: pairs closer than `rest_distance` there never repel
        (default: none are excluded).
    rest_distance : float, optional
        In metres, default ``2 thickness``.
    repulsion : float
        Fraction of the overlap ``thickness - d`` that a pair closer than
        `thickness` is pushed apart per step, in [0, 1] (default 0.1).
    separation : float, optional
        Normal separation that a colliding pair of stage 3 is given at least,
        in metres (default ``0.1 thickness``).
    eta : float, optional
        Contact tolerance of the continuous test, in metres (default
        ``1e-3 thickness``; see :func:`particles.collisions.ccd.first_contact`).
    method : {"gauss-seidel", "jacobi"}
        How the proximity impulses are iterated: one vertex-disjoint colour
        group at a time, or all at once with averaging.
    tol : float
        The proximity iterations stop when no pair would end more than
        ``tol thickness`` short of its target (default 0.01).
    relaxation : float
        Over-relaxation of the Jacobi iterations (>= 1, default 2; Gauss-Seidel
        does not use it): from the second iteration on, a contact's impulse is
        divided by the largest load at its free vertices (``sum |w_j|`` over
        their active contacts) over `relaxation`, never by less than 1,
        instead of by that load. The first iteration averages
        plainly, so an isolated contact or two redundant ones (a vertex above
        the edge between two faces) end at their target without rebounding;
        what is still active after it is a conflict (layers stacked closer
        than the thickness), which plain averaging moves by one layer per
        iteration. 1 is plain averaging throughout.
    strain_limit : ProvotConstraint, optional
        Stretch springs held within ``(1 + s) L0`` inside the treatment (stage 2b,
        :mod:`particles.collisions.strain_limit`), e.g.
        :func:`particles.collisions.strain_limit.strain_limit_from_system`;
        :meth:`from_system` makes it from ``max_strain``. Default: none.
    strain_rounds : int
        Largest number of alternations of the strain limit with the body stage, and of strain limits
        followed by a new continuous test (>= 1, default 8). Both stop as soon as the strain holds;
        around a box (not convex: its edges and corners) the alternations converge slowly, and a sheet
        pinned by an edge and draped over one (40^2) reached 13.5% with 8, within 10% with 24 in the same
        time. Where the limit cannot hold (a pin pulled past it) every step makes them all: a 16^2 curtain
        with a pin pulled 0.3 m away took 0.83 s per step with 8, 6.1 s with 24.
    backend : {None, "auto", "numpy", "numba"}
        Who runs the broad phase, the proximity tests and Jacobi impulses, and the continuous test
        (:mod:`particles.backends`; :mod:`particles.collisions.compiled_stages`: the same contacts and verdicts);
        "auto" compiles from 64 vertices (:data:`particles.collisions.candidate_cache.CLOTH_COLLISION_WEIGHT`).

    Attributes
    ----------
    last : ClothCollisionResult
        Counts of the latest step.
    history : list of ClothCollisionResult
        One per step taken through :meth:`stepper`.
    searches : int
        Candidate searches made so far (the rest of the steps reused the cached pairs).

    Examples
    --------
    A vertex falling 2 cm per step through a triangle 1 cm below it is stopped
    above it:

    >>> from particles.collisions.mesh import TriangleMesh
    >>> mesh = TriangleMesh([[0, 1, 2]], n=4)
    >>> x0 = np.array([[0.0, 0, 0], [1.0, 0, 0], [0.0, 1, 0], [0.2, 0.2, 0.01]])
    >>> x1 = x0.copy(); x1[3, 2] -= 0.02
    >>> cc = ClothCollisions(mesh, thickness=0.005, pinned=[0, 1, 2])
    >>> x, v = cc.resolve(x0, x1, (x1 - x0) / 0.01, t=0.0, h=0.01)
    >>> bool(x[3, 2] >= 0.005 - 1e-12), cc.last.proximity
    (True, 1)
    """

    def __init__(self, mesh, thickness, m=1.0, *, pinned=(), friction=0.0, bodies=(), ccd=True, zones=True,
                 proximity=True, iterations=50, ccd_iterations=10, zone_iterations=100, x_rest=None, rest_distance=None,
                 repulsion=0.1, separation=None, eta=None, method="jacobi", tol=0.01, relaxation=2.0,
                 strain_limit=None, strain_rounds=8, backend=None):
        if not isinstance(mesh, TriangleMesh):
            raise ValueError(f"mesh must be a particles.collisions.mesh.TriangleMesh, got {type(mesh).__name__}")
        self.mesh = mesh
        n = self.n = mesh.n
        self.thickness = positive_number(thickness, "thickness", "metres")
        self.m = np.array(mass_array(m, n))
        self.pinned = pinned_indices(pinned, n)
        self.w = 1.0 / self.m
        self.w[self.pinned] = 0.0
        self.friction = nonnegative_number(friction, "friction")
        if isinstance(bodies, Surface) or hasattr(bodies, "velocity"):
            bodies = [bodies]
        self.bodies = []
        for b in bodies:  # a loop over the few bodies
            if isinstance(b, Surface):
                self.bodies.append(StaticBody(b))
            elif callable(getattr(b, "at", None)) and callable(getattr(b, "velocity", None)):
                self.bodies.append(b)
            else:
                raise ValueError(f"bodies must be Surfaces or moving bodies with .at(t) and .velocity(x, t), "
                                 f"got {type(b).__name__}")
        self.ccd, self.zones, self.proximity = bool(ccd), bool(zones), bool(proximity)
        self.iterations = count(iterations, "iterations", 1)
        self.ccd_iterations = count(ccd_iterations, "ccd_iterations", 0)
        self.zone_iterations = count(zone_iterations, "zone_iterations", 1)
        self.x_rest = None if x_rest is None else np.array(as_float_array(x_rest, "x_rest", shape=(n, 3)))
        self.rest_distance = 2.0 * self.thickness if rest_distance is None else \
            nonnegative_number(rest_distance, "rest_distance", "metres")
        self.repulsion = nonnegative_number(repulsion, "repulsion")
        if self.repulsion > 1:
            raise ValueError(f"repulsion must lie in [0, 1] (a fraction of the overlap per step), got {repulsion!r}")
        self.separation = 0.1 * self.thickness if separation is None else \
            nonnegative_number(separation, "separation", "metres")
        self.eta = 1e-3 * self.thickness if eta is None else positive_number(eta, "eta", "metres")
        self.tol = nonnegative_number(tol, "tol")
        if method not in ("gauss-seidel", "jacobi"):
            raise ValueError(f"method must be 'gauss-seidel' or 'jacobi', got {method!r}")
        self.method = method
        self.relaxation = positive_number(relaxation, "relaxation")
        if self.relaxation < 1:
            raise ValueError(f"relaxation must be at least 1 (1: plain averaging), got {relaxation!r}")
        if strain_limit is not None and (not callable(getattr(strain_limit, "project", None))
                                         or len(getattr(strain_limit, "free", ())) != n):
            raise ValueError(f"strain_limit must be a ProvotConstraint over the mesh's {n} vertices "
                             f"(see strain_limit_from_system), got {type(strain_limit).__name__}")
        self.strain_limit = strain_limit
        self.strain_rounds = count(strain_rounds, "strain_rounds", 1)
        self.last = ClothCollisionResult()
        self.history = []
        self.backend = check_backend(backend)
        self.candidates = CandidateCache(mesh, self.thickness, self.eta, self.backend)

    @property
    def searches(self):
        """Candidate searches made so far (the rest of the steps reused the cached pairs)."""
        return self.candidates.searches

    @classmethod
    def from_system(cls, system, mesh=None, thickness=None, **options):
        """Collisions of a cloth system at its current state (the rest shape), with its masses and pins.

        Parameters
        ----------
        system : MassSpringSystem
            A cloth (:func:`particles.massspring.cloth`) or any 3D system.
        mesh : TriangleMesh, optional
            Default: :meth:`TriangleMesh.grid` of the system's ``grid_shape``.
        thickness : float
            In metres.
        max_strain : float, optional
            A keyword: limit the structural springs' strain to this (Provot's 0.1 for cloth;
            :func:`~particles.collisions.strain_limit.strain_limit_from_system`). Default: no limit.
        **options
            As :class:`ClothCollisions` (``x_rest`` defaults to the current positions).
        """
        if mesh is None:
            shape = getattr(system, "grid_shape", None)
            if shape is None:
                raise ValueError("mesh is needed for a system without a grid_shape")
            mesh = TriangleMesh.grid(shape[1], shape[0])
        if thickness is None:
            raise ValueError("thickness must be given, in metres (e.g. half the grid spacing)")
        options.setdefault("x_rest", system.X[:, 0])
        max_strain = options.pop("max_strain", None)
        if max_strain is not None:
            options["strain_limit"] = strain_limit_from_system(system, max_strain=max_strain,
                                                               backend=options.get("backend"))
        return cls(mesh, thickness, m=system.m, pinned=system.pinned, **options)

    # ----------------------------------------------------------------- helpers
    def _scatter(self, vbar, vertices, weights, impulse):
        """``vbar_j += w_j impulse / m_j`` for the four vertices of each contact, in place."""
        scale = (weights * self.w[vertices]).ravel()
        idx = vertices.ravel()
        for a in range(3):  # per coordinate
            vbar[:, a] += np.bincount(idx, scale * np.repeat(impulse[:, a], 4), minlength=self.n)

    def _relative(self, vbar, vertices, weights):
        return np.einsum("kj,kjd->kd", weights, vbar[vertices])

    def _effective(self, vertices, weights):
        """``sum_j w_j^2 / m_j``: the inverse of the pair's effective mass along a direction."""
        return np.einsum("kj,kj->k", weights ** 2, self.w[vertices])

    # ------------------------------------------------------ stage 3: continuous
    def _drop_fixed(self, impacts):
        keep = self._effective(impacts.vertices, impacts.weights) > 0
        return Impacts(impacts.vertices[keep], impacts.weights[keep], impacts.normal[keep], impacts.time[keep],
                       impacts.edge[keep])

    def _detect(self, x0, vbar, h, moved=None):
        dx = h * vbar
        vf, ee = self.candidates.pairs(x0, dx, 2 * self.eta, moved)
        fast = compiled_stages(self.backend, self.n)
        return self._drop_fixed(detect_pairs(x0, dx - np.median(dx, axis=0), vf, ee, self.eta, fast))

    def _ccd_impulses(self, impacts, x0, vbar, h):
        """Inelastic impulses on colliding pairs, one vertex-disjoint colour group at a time."""
        V, W, N = impacts.vertices, impacts.weights, impacts.normal
        S = self._effective(V, W)
        d0 = dot(N, self._relative(x0, V, W))  # normal separation at the start
        target = np.maximum(0.0, (self.separation - d0) / h)
        for g in color_constraints(V, self.n):  # Gauss-Seidel: one colour at a time
            vN = dot(N[g], self._relative(vbar, V[g], W[g]))
            I = np.maximum(target[g] - vN, 0.0) / S[g]
            self._scatter(vbar, V[g], W[g], I[:, None] * N[g])

    def _continuous(self, x0, vbar, t, h, changed=None):
        """Stages 3 and 4 on ``vbar``, in place.

        With `changed` (shape (n,), bool), the motion was found free of contact before the vertices where it
        holds moved: the first detection tests only the pairs that hold one of them.
        Returns (found, passes, zones, zone vertices, zone passes, anchored, converged).
        """
        found = passes = 0
        zones = zone_vertices = zone_passes = anchored = 0
        converged = True
        if self.ccd:
            impacts, moved = self._detect(x0, vbar, h, changed), None
            for passes in range(1, self.ccd_iterations + 1):  # a loop over detection passes
                if passes > 1:
                    impacts = self._detect(x0, vbar, h, moved)
                if not len(impacts):
                    break
                found += len(impacts)
                self._ccd_impulses(impacts, x0, vbar, h)
                moved = np.zeros(self.n, dtype=bool)
                moved[impacts.vertices.ravel()] = True
                impacts = self._detect(x0, vbar, h, moved) if passes == self.ccd_iterations else Impacts.empty()
            if not self.ccd_iterations:
                found = len(impacts)
            if self.zones:
                zones, zone_vertices, zone_passes, anchored, converged = self._impact_zones(impacts, x0, vbar, t, h)
            else:
                converged = not len(impacts)
        return found, passes, zones, zone_vertices, zone_passes, anchored, converged

    # --------------------------------------------------------------- the step
    def resolve(self, x0, x1, v1, t, h):
        """The treatment of one step from `t` to `t + h`: returns corrected copies of `x1` and `v1`.

        Parameters
        ----------
        x0 : array_like, shape (n, 3)
            Positions at the start of the step (assumed free of intersections), in metres.
        x1, v1 : array_like, shape (n, 3)
            Positions (m) and velocities (m/s) at its end, from the time integrator.
        t : float
            Time at the start of the step, in seconds.
        h : float
            Step length, in seconds (> 0).

        Returns
        -------
        x1, v1 : ndarray, shape (n, 3)
            ``x1 = x0 + h vbar`` and ``v1 + (vbar - vbar_0)``; the counts are in :attr:`last`.
        """
        shape = (self.n, 3)
        x0 = np.ascontiguousarray(as_float_array(x0, "x0", shape=shape))
        x1 = as_float_array(x1, "x1", shape=shape)
        v1 = as_float_array(v1, "v1", shape=shape)
        h = positive_number(h, "h", "seconds")
        t = float(t)
        vbar0 = (x1 - x0) / h
        vbar = np.ascontiguousarray(vbar0.copy())
        nv = ne = npairs = 0
        contacts = None
        if self.bodies:
            nv, ne = self._bodies(x0, vbar, t, h)
        if self.proximity:
            contacts = self._proximity_contacts(x0, vbar, h)
            npairs = self._proximity(contacts, x0, vbar, t, h)
            if self.bodies:
                self._bodies(x0, vbar, t, h)
        sweeps = rounds = 0
        clean = None  # vbar where the last continuous test ended without a contact
        for rounds in range(1, self.strain_rounds + 1):  # a loop over strain limits, each closed by the ccd
            if self.strain_limit is not None:
                sweeps += self._limit_strain(x0, vbar, t, h)
            changed = None if clean is None else np.any(vbar != clean, axis=1)  # what the limit moved since
            counts = self._continuous(x0, vbar, t, h, changed)
            if self.strain_limit is None or not counts[-1] or self._holds(self._strain(x0, vbar, h)):
                break
            clean = vbar.copy()
        self.last = ClothCollisionResult(nv, ne, npairs, *counts, sweeps, rounds, self._strain(x0, vbar, h))
        return x0 + h * vbar, v1 + (vbar - vbar0)

    def stepper(self, step):
        """Wrap a stepper or solver so that every step ends with the treatment of :meth:`resolve`.

        Parameters
        ----------
        step : str, callable or solver
            A stepper ``step(f, X, t, h)``, a name of
            :data:`particles.integrators.INTEGRATORS`, a solver object
            (:class:`particles.implicit.Prefactored`, :class:`particles.xpbd.XPBD`, ...)
            or another wrapper (:meth:`particles.constraints.ProvotConstraint.stepper`).

        Returns
        -------
        callable
            A stepper ``(f, X, t, h) -> X_new`` with the order and layout of
            `step`; each step sets :attr:`last` and appends it to :attr:`history`.
        """

        def fix(X_old, X_new, t, h):
            x, v = self.resolve(X_old[:, 0], X_new[:, 0], X_new[:, 1], t, h)
            self.history.append(self.last)
            X_new[:, 0], X_new[:, 1] = x, v
            return X_new

        return after(step, fix, "cloth_collisions")

    def pairs_closer_than(self, x, distance=None):
        """Distances of the vertex-face and edge-edge pairs closer than `distance` (not rest neighbours).

        Parameters
        ----------
        x : array_like, shape (n, 3)
            Positions, in metres.
        distance : float, optional
            Default: `thickness`.

        Returns
        -------
        ndarray, shape (p,)
            The distances, in metres (pairs with a common vertex, and rest
            neighbours when `x_rest` was given, left out).
        """
        x = np.ascontiguousarray(as_float_array(x, "x", shape=(self.n, 3)))
        distance = self.thickness if distance is None else positive_number(distance, "distance", "metres")
        vf, ee = candidate_pairs(self.mesh, x, x, 0.5 * distance)
        out = []
        for idx, edge in ((vf, False), (ee, True)):  # the two kinds of pairs
            if len(idx):
                p = x[idx]
                d = (edge_edge_kernel if edge else vertex_face_kernel)(p[:, 0], p[:, 1], p[:, 2], p[:, 3]).distance
                d, idx = d[d < distance], idx[d < distance]
                out.append(d[self._rest_far(idx, edge)])
        return np.concatenate(out) if out else np.zeros(0)
