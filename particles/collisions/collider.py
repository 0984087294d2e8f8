"""Collisions with implicit surfaces: detection, response, and the overshooting problem.

**Detection.** A particle is inside a solid when ``H(x) < 0`` (see
:mod:`particles.collisions.surfaces`: :class:`Plane`, :class:`Sphere`, :class:`Box` and
their unions, intersections and complements, re-exported here).

**Response.** Split the velocity at the contact along the unit normal ``n``:
``v_n = (v . n) n`` and ``v_t = v - v_n``. The tangential part is kept (or
reduced by Coulomb friction), the normal part is reflected and scaled by the
coefficient of restitution ``eps``::

    v  <-  v_t - eps v_n         impulse  J = -m (1 + eps) v_n

``eps = 1`` is a perfectly elastic bounce, ``eps = 0`` a dead stop along the
normal (cloth on a body).

**Overshooting.** Collisions are detected after a step, when the particle is
already inside. Two fixes, selected by ``method``:

* ``"project"``: the quick fix, move the particle to the closest surface
  point and reflect its velocity there. It changes the energy by up to
  ``m |g| |v| h`` per bounce (a ball on a floor gains height).
* ``"backtrack"``: find *when* in the step the path crossed ``H = 0``,
  respond there, and advance the rest of the step. Positions within the step
  come from the cubic Hermite interpolant of the step's end states (exact for
  constant forces, fourth-order accurate otherwise, no extra force
  evaluations); the rest of the step uses the step's mean acceleration
  ``(v1 - v0) / h``. With ``eps = 1`` a ball keeps its bounce height.

The functions work on arrays, independently of any system class, so a cloth
solver can call ``collider.collide(X_old, X_new, t, h, m=m, pinned=pinned)``
after each of its steps.

References
----------
.. [1] A. Witkin and D. Baraff, "Physically Based Modeling: Principles and
   Practice", SIGGRAPH 1997 course notes, "Particle System Dynamics", section 5
   (collisions and contact).
.. [2] R. Bridson, R. Fedkiw and J. Anderson, "Robust treatment of collisions,
   contact and friction for cloth animation", ACM SIGGRAPH 2002 (Coulomb
   friction as a velocity impulse bounded by the normal impulse).
"""

from dataclasses import dataclass

import numpy as np

from .._checks import as_float_array, mass_array, nonnegative_number, pinned_indices, positive_number
from .._checks import restitution_coefficient
from .._vectors import rowdot
from ..backends import check_backend, compiled
from ..integrators.solvers import after
from .response import response
from .surface_crossing import cubic_path, first_crossing, hermite, hermite_coefficients, path_speed
from .surfaces import Box, Cylinder, Plane, Sphere, Surface

__all__ = ["Contacts", "Collider"]

METHODS = ("project", "backtrack")
ROUNDOFF_DEPTH = 1e-12
"""Depth (m) below which a particle that gets no impulse counts as on the surface, not in contact."""
_PRIMITIVES = (Plane, Sphere, Box, Cylinder)  # their normal at a point inside points to its closest point


@dataclass
class Contacts:
    """The collisions found during one call, one row per contact.

    A particle that bounces twice within a step appears twice. Only
    responses with an impulse are contacts: a particle left on the surface
    by round-off that leaves it, or rests on it without impulse, is not
    logged (``len(contacts)`` counts bounces).

    Attributes
    ----------
    index : ndarray of int, shape (k,)
        Particle indices.
    time : ndarray, shape (k,)
        Time of each contact, in seconds (the end of the step for ``"project"``).
    point : ndarray, shape (k, d)
        Contact positions, on the surface.
    normal : ndarray, shape (k, d)
        Unit normals there.
    impulse : ndarray, shape (k, d)
        Normal impulse ``-m (1 + eps) v_n``, in N s.
    friction : ndarray, shape (k, d)
        Tangential (friction) impulse, in N s.
    """

    index: np.ndarray
    time: np.ndarray
    point: np.ndarray
    normal: np.ndarray
    impulse: np.ndarray
    friction: np.ndarray

    @classmethod
    def empty(cls, d):
        """No contacts.

        Parameters
        ----------
        d : int
            Dimension of space, 2 or 3.

        Returns
        -------
        Contacts
            With ``index`` and ``time`` of shape (0,) and the vectors of shape (0, d).
        """
        return cls(np.zeros(0, dtype=int), np.zeros(0), *(np.zeros((0, d)) for _ in range(4)))

    @classmethod
    def concatenate(cls, parts, d):
        """All the contacts of several calls (e.g. the steps of a run), in order.

        Parameters
        ----------
        parts : sequence of Contacts
            Each with vectors of shape (k_i, d); empty ones are skipped.
        d : int
            Dimension of space, for the result when there are no contacts.

        Returns
        -------
        Contacts
            Rows of shape (sum k_i,) and (sum k_i, d), the parts one after the other.
        """
        parts = [p for p in parts if len(p)]
        if not parts:
            return cls.empty(d)
        return cls(*(np.concatenate([getattr(p, f) for p in parts]) for f in
                     ("index", "time", "point", "normal", "impulse", "friction")))

    def __len__(self):
        return len(self.index)

    def total_impulse(self):
        """Sum of all normal and friction impulses, shape (d,), in N s."""
        return self.impulse.sum(axis=0) + self.friction.sum(axis=0)


class Collider:
    """Collisions of particles with one implicit surface, applied after each step.

    Parameters
    ----------
    surface : Surface
        The solid (inside where ``H < 0``); combine several with ``|``.
    restitution : float
        Coefficient of restitution ``eps`` in [0, 1].
    friction : float
        Coulomb friction coefficient ``mu`` >= 0.
    method : {"backtrack", "project"}
        The fix for overshooting (see the module notes).
    max_bounces : int
        Backtracking: largest number of contacts per particle within one step
        (a corner, a resting particle). Particles still inside afterwards are
        projected, so that no particle ends a step inside the solid.
    samples : int
        Backtracking: points per step at which the path is tested for its
        first entry into the solid (a path that crosses a solid thinner than
        ``|v| h / samples`` between two samples can be missed).
    backend : {None, "auto", "numpy", "numba"}, optional
        Who fixes the steps of :meth:`stepper` (and :meth:`run`): this NumPy
        code, or the same per particle compiled, in place on the step's end
        state, for a :class:`Plane`, :class:`Sphere`, :class:`Box` or
        :class:`~particles.collisions.surfaces.Cylinder` (combinations stay on NumPy);
        see :mod:`particles.backends` (None: the global choice).
        :meth:`collide` and :meth:`resolve` are always the NumPy reference.

    Notes
    -----
    Resting contact: after a bounce that is too slow to leave the surface
    before the step ends, the inward part of the acceleration is cancelled
    for the rest of the step (the surface pushes back), which stops the
    infinitely many ever smaller bounces of an ideal inelastic ball from
    costing ever more work.

    Examples
    --------
    >>> import numpy as np
    >>> floor = Collider(Plane([0.0, 0.0], [0.0, 1.0]), restitution=0.5)
    >>> X_old = np.array([[[0.0, 0.1], [1.0, -2.0]]])   # one particle, 0.1 m up, falling
    >>> X_new = np.array([[[0.1, -0.1], [1.0, -2.0]]])  # a step of 0.1 s without forces
    >>> X, contacts = floor.collide(X_old, X_new, t=0.0, h=0.1)
    >>> X[0].round(12).tolist(), contacts.time.round(12).tolist()
    ([[0.1, 0.05], [1.0, 1.0]], [0.05])
    """

    def __init__(self, surface, restitution=1.0, friction=0.0, method="backtrack", max_bounces=4, samples=8,
                 backend=None):
        self.backend = check_backend(backend)
        self.compiled_buffers = {}  # the compiled fix's work arrays (particles.collisions.collider_kernels), by name
        if not isinstance(surface, Surface):
            raise ValueError(f"surface must be a Surface (Plane, Sphere, Box, ...), got {type(surface).__name__}")
        self.surface = surface
        self.restitution = restitution_coefficient(restitution)
        self.friction = nonnegative_number(friction, "friction")
        if method not in METHODS:
            raise ValueError(f"unknown method {method!r}; expected one of {', '.join(map(repr, METHODS))}")
        self.method = method
        self.max_bounces = _count(max_bounces, "max_bounces")
        self.samples = _count(samples, "samples")

    def __repr__(self):
        return (f"Collider({self.surface!r}, restitution={self.restitution}, friction={self.friction}, "
                f"method={self.method!r})")

    def _check(self, X, name):
        X = as_float_array(X, name, ndim=3)
        if X.shape[1] != 2 or X.shape[2] != self.surface.d:
            raise ValueError(f"{name} must have shape (n, 2, {self.surface.d}), got shape {X.shape}")
        return X

    def _free(self, n, pinned):
        """Mask of the particles that collide: all but the pinned ones (indices or a mask)."""
        free = np.ones(n, dtype=bool)
        free[pinned_indices(pinned, n)] = False
        return free

    def resolve(self, x, v, m=1.0, pinned=(), t=0.0):
        """Project particles inside the solid onto its surface and reflect their velocities.

        Parameters
        ----------
        x, v : array_like, shape (n, d)
            Positions and velocities (not modified).
        m : float or array_like, shape (n,)
            Masses, in kg, > 0, for the impulses.
        pinned : array_like of int or bool
            Particles left untouched.
        t : float
            Time recorded in the contacts.

        Returns
        -------
        x, v : ndarray, shape (n, d)
            Corrected copies.
        contacts : Contacts
        """
        x = np.array(as_float_array(x, "x", ndim=2), order="K")
        v = np.array(as_float_array(v, "v", shape=x.shape), order="K")
        m = mass_array(m, len(x))
        return self._project(x, v, m, self._free(len(x), pinned), float(t))

    def _project(self, x, v, m, free, t):
        """Project the free particles inside the solid, in place; returns x, v and the contacts.

        A particle that is inside only by round-off (``H >= -ROUNDOFF_DEPTH``,
        e.g. on a contact point computed in the step) and is not approaching
        is moved onto the surface but not logged: no impulse, no contact.
        """
        idx = np.flatnonzero(free)
        H = self.surface._H(x[idx])
        inside = H < 0
        idx, H = idx[inside], H[inside]
        if not len(idx):
            return x, v, Contacts.empty(x.shape[1])
        p = self.surface._closest(x[idx])
        n = _push_directions(self.surface, x[idx], p)
        v_new, dv_n, dv_t = response(v[idx], n, self.restitution, self.friction)
        x[idx], v[idx] = p, v_new
        mi = m[idx, None]
        log = _changed(dv_n, dv_t) | (H < -ROUNDOFF_DEPTH)
        return x, v, Contacts(idx[log], np.full(log.sum(), t), p[log], n[log], (mi * dv_n)[log], (mi * dv_t)[log])

    def collide(self, X_old, X_new, t, h, m=1.0, pinned=()):
        """Fix the collisions of one step from `t` to `t + h`.

        Parameters
        ----------
        X_old, X_new : array_like, shape (n, 2, d)
            States at the start and the end of the step (not modified).
        t : float
            Time at the start of the step, in seconds.
        h : float
            Step length, in seconds.
        m : float or array_like, shape (n,)
            Masses, in kg, > 0 (only used for the reported impulses).
        pinned : array_like of int or bool
            Particles left untouched (pinned cloth corners).

        Returns
        -------
        X : ndarray, shape (n, 2, d)
            Corrected end state, in the memory order of `X_new`; every free
            particle has ``H >= 0`` (up to round-off in the surface point).
        contacts : Contacts
        """
        X_old = self._check(X_old, "X_old")
        X_new = self._check(X_new, "X_new")
        if X_old.shape != X_new.shape:
            raise ValueError(f"X_old and X_new must have the same shape, got {X_old.shape} and {X_new.shape}")
        h = positive_number(h, "h", "seconds")
        free = self._free(len(X_new), pinned)
        m = mass_array(m, len(X_new))
        return self._collide(X_old, X_new.copy(order="K"), float(t), h, m, free)

    def _collide(self, X_old, X, t, h, m, free):
        """:meth:`collide` on checked arguments; `X` (the end state) is corrected in place."""
        if self.method == "project":
            x, v, contacts = self._project(X[:, 0], X[:, 1], m, free, t + h)
            X[:, 0], X[:, 1] = x, v
            return X, contacts
        return self._backtrack(X_old, X, t, h, m, free)

    def _backtrack(self, X_old, X, t, h, m, free):
        """Find the entry time on the Hermite path, respond there, advance the rest, repeat."""
        idx = np.flatnonzero(free)
        idx = idx[self._may_enter(X_old[idx], X[idx], h)]
        x0, v0 = X_old[idx, 0], X_old[idx, 1]
        x1, v1 = X[idx, 0], X[idx, 1]
        t0, dt = np.full(len(idx), t), np.full(len(idx), h)
        a = (v1 - v0) / h  # mean acceleration of the step, used for the rest of it
        found = []
        todo = np.arange(len(idx))  # paths that may still cross: all, then those that just bounced
        for _ in range(self.max_bounces):  # a loop over successive bounces within the step
            if not len(todo):
                break
            c = hermite_coefficients(x0[todo], v0[todo], x1[todo], v1[todo], dt[todo])
            s, s_in = first_crossing(self.surface, lambda k, s: cubic_path(c, k, s), len(todo), samples=self.samples,
                                     speed=path_speed(x0[todo], v0[todo], x1[todo], v1[todo], dt[todo]))
            crossed = s < 1.0
            hit, s, s_in = todo[crossed], s[crossed], s_in[crossed]
            xc, vc = hermite(x0[hit], v0[hit], x1[hit], v1[hit], dt[hit], s)
            x_in, _ = hermite(x0[hit], v0[hit], x1[hit], v1[hit], dt[hit], s_in)
            n = self.surface.normal(x_in) if len(hit) else xc  # the face crossed, unambiguous at corners
            v_new, dv_n, dv_t = response(vc, n, self.restitution, self.friction)
            rest = (1.0 - s) * dt[hit]
            ah = a[hit].copy()
            a_n = rowdot(ah, n)
            resting = (a_n < 0) & (rowdot(v_new, n) < -a_n * rest)
            ah[resting] -= a_n[resting, None] * n[resting]  # the surface carries the inward pull
            if self.friction and resting.any():
                ah[resting] -= _resting_friction(v_new[resting], ah[resting], n[resting], -a_n[resting],
                                                 rest[resting], self.friction)
            tc = t0[hit] + s * dt[hit]
            mi = m[idx[hit], None]
            # a crossing whose response changes nothing (a path that starts on the surface by round-off,
            # leaving it) is no contact: not logged, its path left as it is, not tested again
            real = _changed(dv_n, dv_t)
            found.append(Contacts(idx[hit][real], tc[real], xc[real], n[real], (mi * dv_n)[real],
                                  (mi * dv_t)[real]))
            keep = real | resting  # a resting particle without impulse still has its pull cancelled
            hit, xc, v_new, ah, rest, tc = hit[keep], xc[keep], v_new[keep], ah[keep], rest[keep], tc[keep]
            # the rest of the step: constant acceleration from the contact state
            x0[hit], v0[hit] = xc, v_new
            x1[hit] = xc + v_new * rest[:, None] + 0.5 * ah * rest[:, None] ** 2
            v1[hit] = v_new + ah * rest[:, None]
            t0[hit], dt[hit] = tc, np.maximum(rest, 1e-300)
            todo = hit[real[keep]]
        X[idx, 0], X[idx, 1] = x1, v1
        x, v, projected = self._project(X[:, 0], X[:, 1], m, free, t + h)
        X[:, 0], X[:, 1] = x, v
        found.append(projected)
        return X, Contacts.concatenate(found, X.shape[2])

    def _may_enter(self, X0, X1, h):
        """Which paths start outside and may touch the solid during the step (cheap, conservative).

        A path ending inside does. For one with both ends outside, ``H`` can
        only drop ``L D s`` in ``s`` from the start and ``L D (1 - s)`` from
        the end, where ``L`` bounds ``|grad H|`` (1 for signed distances) and
        ``D`` bounds ``|dx/ds|`` (see :func:`particles.collisions.surface_crossing.path_speed`); so it stays
        positive when ``H(x0) + H(x1) > L D``.
        """
        H0, H1 = self.surface._H(X0[:, 0]), self.surface._H(X1[:, 0])
        maybe = (H0 >= 0) & (H1 < 0)
        L = self.surface.lipschitz
        if L is None:
            return (H0 >= 0)
        D = path_speed(X0[:, 0], X0[:, 1], X1[:, 0], X1[:, 1], h)
        return maybe | ((H0 >= 0) & (H0 + H1 <= L * D * (1 + 1e-12) + 1e-15))

    def stepper(self, step, m=1.0, pinned=()):
        """Wrap a stepper so that every step ends with this collision fix.

        The returned ``stepper(f, X, t, h)`` composes with other wrappers and
        with the implicit mass-spring solvers, e.g. a cloth on a body with
        Provot's constraint::

            provot = ProvotConstraint.from_system(cloth)
            step = collider.stepper(provot.stepper(symplectic_euler), m=cloth.m, pinned=cloth.pinned)
            cloth.run(2.0, h, method=step)

        Collisions come last, so that no free particle ends a step inside the
        solid. The contacts of the latest step are kept in ``step.contacts``.
        When the collider's backend resolves to numba and the surface is a
        primitive, the fix is compiled (:func:`particles.collisions.collider_kernels.collide`):
        the same contacts and end states as :meth:`collide`, to the bit, the
        step's end state corrected in place.

        Parameters
        ----------
        step : str, callable or solver
            A stepper ``step(f, X, t, h)``, a name of
            :data:`particles.integrators.INTEGRATORS` or a solver object
            (see :mod:`particles.integrators.solvers`).
        m : float or array_like, shape (n,)
            Masses, in kg (for the reported impulses).
        pinned : array_like of int or bool
            Particles left untouched.

        Returns
        -------
        callable
            A stepper ``(f, X, t, h) -> X_new`` with the order and layout of
            `step`, and ``contacts``: the :class:`Contacts` of its latest step.
        """
        kept = {}  # the masses and the free mask, per particle count

        def collide(X_old, X_new, t, h):
            if compiled(self.backend, len(X_new)) and X_old.shape == X_new.shape == (len(X_new), 2, self.surface.d) \
                    and X_new.dtype == X_old.dtype == np.float64:
                from .collider_kernels import collide as compiled_collide  # noqa: PLC0415  (imports numba)
                if kept.get("n") != len(X_new):
                    kept.update(n=len(X_new), m=np.ascontiguousarray(mass_array(m, len(X_new))),
                                free=self._free(len(X_new), pinned))
                found = compiled_collide(self, X_old, X_new, t, positive_number(h, "h", "seconds"), kept["m"],
                                         kept["free"])
                if found is not None:  # a primitive surface: fixed in place, compiled
                    fixed.contacts = Contacts(*found)
                    return X_new
            X_new, fixed.contacts = self.collide(X_old, X_new, t, h, m=m, pinned=pinned)
            return X_new

        fixed = after(step, collide, "collisions")
        fixed.contacts = Contacts.empty(self.surface.d)
        return fixed

    def run(self, system, t_end, h, method="verlet", every=1):
        """Simulate a :class:`particles.ParticleSystem` with collisions after every step.

        A thin wrapper of :meth:`particles.ParticleSystem.run` with the
        stepper of :meth:`stepper`, collecting the contacts of every step::

            step = collider.stepper(method, m=system.m, pinned=system.pinned)
            t, X = system.run(t_end, h, method=step, every=every,
                              between_steps=lambda system, t0: found.append(step.contacts))

        Parameters
        ----------
        system : ParticleSystem
            Advanced in place to `t_end`.
        t_end : float
            End time, in seconds.
        h : float
            Time step, in seconds (the last step is shortened to land on `t_end`).
        method : str, callable or solver
            What takes each step (see :mod:`particles.integrators.solvers`).
        every : int
            Record every `every`-th state (first and last always recorded).

        Returns
        -------
        t : ndarray, shape (K,)
        X : ndarray, shape (K, n, 2, d)
        contacts : Contacts
            All contacts of the run.

        Raises
        ------
        SimulationDiverged
            As :meth:`particles.ParticleSystem.run`; the system keeps the
            state at the start of the failing step.
        """
        step = self.stepper(method, m=system.m, pinned=system.pinned)
        found = []
        t, X = system.run(t_end, h, method=step, every=every,
                          between_steps=lambda system, t0: found.append(step.contacts))
        return t, X, Contacts.concatenate(found, system.d)


def _changed(dv_n, dv_t):
    """Rows of a response that change the velocity: a non-zero normal or friction impulse."""
    return np.any(dv_n != 0, axis=1) | np.any(dv_t != 0, axis=1)


def _resting_friction(v, a_t, n, pressure, tau, mu):
    """Friction deceleration of particles resting on the surface for the rest of the step.

    The surface pushes with ``m * pressure`` (the inward acceleration it
    cancels), so Coulomb friction can remove up to ``mu * pressure * tau`` of
    tangential velocity over the remaining time ``tau``, never reversing it:
    static friction when that is enough, kinetic friction otherwise.

    Returns the constant acceleration to subtract, shape (k, d).
    """
    v_t = v - rowdot(v, n)[:, None] * n
    v_end = v_t + a_t * tau[:, None]  # tangential velocity at the end of the step without friction
    speed = np.sqrt(rowdot(v_end, v_end))
    removed = np.minimum(speed, mu * pressure * tau)
    scale = np.divide(removed, speed * tau, out=np.zeros_like(speed), where=(speed > 0) & (tau > 0))
    return scale[:, None] * v_end


def _push_directions(surface, x, p):
    """Unit vectors from inside points `x` to their surface points `p` (the normal there).

    For the primitives (:class:`Plane`, :class:`Sphere`, :class:`Box`,
    :class:`~particles.collisions.surfaces.Cylinder`) that is the normal at ``x``
    itself, which the surface computes without subtracting two points that
    may be a rounding error apart (``(p - x) / |p - x|`` for a particle
    ``1e-5`` m deep is only good to ``1e-11``). For combined surfaces: ``p -
    x``, normalized, or the gradient at ``x`` where ``p`` is too close to
    ``x`` to give a direction. Unlike the gradient at ``p``, either is
    unambiguous at the edges and corners of a box.
    """
    if type(surface) in _PRIMITIVES:
        return surface.normal(x)
    n = p - x
    norm = np.sqrt(rowdot(n, n))
    ok = norm > 1e-12 * (1.0 + np.abs(p).max(axis=1, initial=0.0))
    n[ok] /= norm[ok, None]
    if not ok.all():
        n[~ok] = surface.normal(x[~ok])
    return n


def _count(value, name):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ValueError(f"{name} must be a positive integer, got {value!r}")
    return int(value)
