"""The compiled symplectic Euler step of a mass-spring system: what each force is, the blocks, the kernel's call.

:class:`particles.massspring.MassSpringSystem` runs symplectic Euler with
this step where its springs run compiled (:meth:`~particles.massspring.MassSpringSystem.stepper`
chooses it, once, when the system runs: the generic stepper knows nothing of
it). :class:`CompiledStep` takes the step in one parallel pass over blocks of
particles (:mod:`particles.massspring.step_kernels`): the springs
(:class:`~particles.forces.Springs`, up to three sets, with their damping),
the bending joints (:class:`~particles.forces.Bending`) and the update of
every particle compiled, with air damping (:class:`~particles.forces.Damping`),
wind (:class:`~particles.forces.Wind`, gusts too) and uniform gravity folded
into the update; clamps (:class:`~particles.forces.Clamp`) by a compiled
kernel of their own; every other force added by its own ``add_to`` as in
:meth:`~particles.ParticleSystem.total_force`. It agrees with the NumPy step
to rounding (about 1e-16 relative: the forces are summed in another order,
with fused multiply-adds) and has the same bits on any number of threads.
Importing this module imports numba.
"""

import sys

import numpy as np

from .._checks import indices_fit
from ..backends import compiled, get_backend
from ..backends.compile import pick
from .step_kernels import GUST, PER_MASS, PHASE, WAVELENGTH, clamp_pass, symplectic_euler_steps

__all__ = ["CompiledStep", "StepParts", "STEP_BLOCK"]


def _per_spring(a, s):
    """A spring set's parameter as the kernel reads it: float64, contiguous, one per spring (a scalar spread)."""
    a = np.ascontiguousarray(a, dtype=np.float64)
    return a if a.shape == (s,) else np.ascontiguousarray(np.broadcast_to(a, (s,)))


def _count_alone():
    """The reference count of an object held by a list only, read as :meth:`CompiledStep._new_state` reads it."""
    for probe in [object()]:  # the same holders: the list, the loop variable, the call's argument
        return sys.getrefcount(probe)


_ALONE = _count_alone()

# particles per block of the compiled step's spring pass: a number set by the system, not the threads
STEP_BLOCK = 2048


class StepParts:
    """What the compiled step does with each of a system's forces (:meth:`CompiledStep.parts`).

    Attributes
    ----------
    sets : list of Springs
        One to three spring sets, computed in the block pass.
    bending : Bending or None
        One bending set, computed in the block pass.
    G : ndarray, shape (d,)
        The sum of the uniform gravities, added to every free particle's acceleration.
    D, R : float
        Air damping, ``F -= (D + R m) v``: the sum of the coefficients ``d`` (kg/s) and of the rates (1/s).
    winds : list of Wind
        Computed in the particles' update.
    clamps : list of Clamp
        Computed by their own compiled kernel before the pass.
    others : list of Force
        Forces without a compiled form, added by their own ``add_to`` before the pass.
    """

    def __init__(self, d):
        self.sets, self.bending, self.G, self.D, self.R = [], None, np.zeros(d), 0.0, 0.0
        self.winds, self.clamps, self.others = [], [], []


class CompiledStep:
    """A mass-spring system's symplectic Euler step in one compiled pass (see the module notes).

    Parameters
    ----------
    system : MassSpringSystem
        The system whose forces the step computes; it keeps this object (its
        layout of the springs in blocks, its spare states) from step to step.
    """

    def __init__(self, system):
        self.system = system
        self._spare = []  # earlier new states, reused once nobody holds them
        self._key = self._layout_kept = None

    @staticmethod
    def runs_compiled(forces, n):
        """Whether every one of `forces` runs on the compiled kernels for `n` particles (each by its backend)."""
        return all(compiled(backend, n) for backend in {f._backend for f in forces})

    @staticmethod
    def automatic(forces):
        """Whether one of `forces` leaves the choice to ``"auto"`` (its own backend or the global choice)."""
        return any((get_backend() if f._backend is None else f._backend) == "auto" for f in forces)

    def parts(self, n):
        """The :class:`StepParts` of the system's forces; None when the step does not apply.

        By :attr:`~particles.forces.force.Force.compiled_role`: up to three
        :class:`~particles.forces.Springs` sets, all resolving to numba, in
        2D or 3D; one :class:`~particles.forces.Bending` set that resolves
        to numba; gravity, damping, wind and clamps of the system's
        dimension; the rest added by their own ``add_to``. When a spring
        set's backend is ``"auto"`` (its own or the global choice), the step
        applies only if it covers every force (no ``others``): a force left
        to NumPy would read the compiled step's C-ordered state with NumPy's
        slow strided loops, and the NumPy step is then faster.
        """
        d = self.system.d
        found = StepParts(d)
        for force in self.system.forces:  # a loop over the system's few forces
            role = getattr(force, "compiled_role", None)
            if role == "springs":
                found.sets.append(force)
            elif role == "gravity" and np.shape(force.g) == (d,):
                found.G += force.g
            elif role == "damping":
                found.D, found.R = (found.D + force.d, found.R) if force.rate is None else (found.D, found.R + force.rate)
            elif role == "wind" and np.shape(force.strength) == (d,):
                found.winds.append(force)
            elif role == "bending" and found.bending is None and self.runs_compiled([force], n):
                found.bending = force
            elif role == "clamp" and force.direction.shape[1:] == (d,):
                found.clamps.append(force)
            else:
                found.others.append(force)
        sets = found.sets
        if not sets or len(sets) > 3 or d not in (2, 3) or not self.runs_compiled(sets, n):
            return None
        if found.others and self.automatic(sets):
            return None
        return found

    def _layout(self, sets, bending, n):
        """The springs by lower end (compressed rows), the springs entering each block, the joints touching
        each block, and the blocks' windows.

        Kept on the system until the spring sets, the bending set or the
        particle count change; their parameters (``rest_length``, ``k``,
        ``kd``, ``kb``, ``rest_angle``) are read at every step.
        """
        key = (n, tuple((id(f.i), id(f.j), len(f.i)) for f in sets),
               None if bending is None else (id(bending.i), id(bending.j), id(bending.l), len(bending.i)))
        if self._key == key:
            return self._layout_kept
        blocks = max(1, min(64, n // STEP_BLOCK))
        start = np.arange(blocks + 1) * n // blocks
        a = np.concatenate([np.minimum(f.i, f.j) for f in sets])
        order = np.argsort(a, kind="stable")
        a = a[order]
        nbr = np.concatenate([np.maximum(f.i, f.j) for f in sets])[order]
        which = np.concatenate([np.full(len(f.i), q, dtype=np.uint8) for q, f in enumerate(sets)])[order]
        sidx = np.concatenate([np.arange(len(f.i), dtype=np.uint32) for f in sets])[order]
        ptr = np.searchsorted(a, np.arange(n + 1))
        block_a = np.searchsorted(start, a, side="right") - 1
        block_b = np.searchsorted(start, nbr, side="right") - 1
        # the springs that enter block c from an earlier one, by upper end: rows of that block too (the force
        # on the lower end, outside the block, falls on a row of its window that is never used)
        entering = np.flatnonzero(block_b != block_a)
        entering = entering[np.argsort(nbr[entering], kind="stable")]
        inrow, first = np.unique(nbr[entering], return_index=True)
        bounds = np.append(first, len(entering))  # the entering springs of row u: bounds[u]:bounds[u + 1]
        incount = np.diff(bounds)
        rin = np.searchsorted(inrow, start)
        count = np.diff(ptr)
        rowp, rcount, ends, entries = [], [], [], []
        lo, hi = start[:-1].copy(), start[1:].copy()
        for c in range(blocks):  # a loop over the blocks: each one's rows (its particles, then the entering ends)
            own = np.arange(ptr[start[c]], ptr[start[c + 1]])
            enter = entering[bounds[rin[c]]:bounds[rin[c + 1]]]
            rowp += [np.arange(start[c], start[c + 1]), inrow[rin[c]:rin[c + 1]]]
            rcount += [count[start[c]:start[c + 1]], incount[rin[c]:rin[c + 1]]]
            ends += [nbr[own], a[enter]]
            entries += [own, enter]
            lo[c] = min(lo[c], a[enter].min(initial=n))
            hi[c] = max(hi[c], nbr[own].max(initial=0) + 1)
        joints = _joints(bending, start, lo, hi)
        entries = np.concatenate(entries)
        rb0 = np.concatenate([[0], np.cumsum([len(r) for r in rowp[1::2]]) + start[1:]])
        rptr = np.concatenate([[0], np.cumsum(np.concatenate(rcount))])
        row0 = np.concatenate([[0], np.cumsum(hi - lo)])
        d = self.system.d
        layout = dict(start=start, lo=lo, hi=hi, row0=row0,
                      fw=np.empty((row0[-1], d)), pinned=None, joints=joints, other=np.zeros((1, d)),
                      rows=(rb0, np.concatenate(rowp).astype(np.uint32), rptr.astype(np.uint32),
                            np.concatenate(ends).astype(np.uint32), which[entries], sidx[entries]))
        self._key, self._layout_kept = key, layout
        return layout

    def _new_state(self, shape):
        """An array for a new state (C order, which the next step reads faster): an earlier one if free, else new.

        A run holds the state it steps from and drops the one before, so two
        arrays take turns (three when steps run in one call,
        :meth:`symplectic_euler_steps`, which writes two). One is free when this list is its only holder
        (CPython's reference count, compared with that of an object only a
        list holds, :data:`_ALONE`), and then no one can see it change; a new
        array costs a page fault per 4 KiB when first written (about a tenth
        of the step at 128^2).
        """
        for spare in self._spare:  # a loop over at most three arrays
            if spare.shape == shape and sys.getrefcount(spare) == _ALONE:
                return spare
        out = np.empty(shape)
        self._spare[:] = [out] + self._spare[:2]
        return out

    def _other(self, found, layout, X, t):
        """The forces computed before the pass, (n, d) (clamps compiled, the others by add_to); None if none."""
        if not found.clamps and not found.others:
            return None
        n, d = X.shape[0], X.shape[2]
        other = layout["other"]
        if other.shape != (n, d):
            other = layout["other"] = np.zeros((n, d))
        else:
            other.fill(0.0)
        x = X[:, 0]
        for clamp in found.clamps:  # a loop over the few clamps' sets (a hair has one)
            indices_fit(clamp._highest, n, "pairs")
            clamp_pass(other, x, clamp.i, clamp.j, clamp.direction, _per_spring(clamp.kb, len(clamp.i)))
        for force in found.others:  # a loop over the other forces: each adds its own, as in total_force
            force.add_to(other, x, X[:, 1], t, self.system.m)
        return other

    def _prepared(self, X):
        """What a step from X needs, ``(found, layout, arrays)``; None when the compiled step does not apply."""
        system = self.system
        n = system.n
        if X.shape != system.X.shape or X.dtype != np.float64 or (found := self.parts(n)) is None:
            return None
        sets, bending = found.sets, found.bending
        for f in sets + ([] if bending is None else [bending]):  # a loop over the few spring and bending sets
            indices_fit(f._highest, n, "indices")
        layout = self._layout(sets, bending, n)
        arrays = [_per_spring(a, len(f.i)) for f in sets for a in (f.rest_length, f.k, f.kd)]
        arrays += arrays[:3] * (3 - len(sets))  # unused slots (no entry refers to them)
        joints = layout["joints"]
        if bending is None:
            arrays += [*joints, np.zeros(0), np.zeros(0)]
        else:
            b = len(bending.i)
            arrays += [*joints, _per_spring(bending.kb, b), _per_spring(bending.rest_angle, b)]
        pinned = system.pinned
        if layout["pinned"] is None or pinned.shape != layout["pinned"].shape or not (pinned == layout["pinned"]).all():
            layout["free"] = np.ones(n, dtype=np.bool_)
            layout["free"][system.pinned] = False
            layout["pinned"] = system.pinned.copy()
        return found, layout, arrays

    def _steps(self, prepared, X, ts, hs, other, limit, out0, out1):
        """The kernel's steps from X at the times `ts` by `hs` (see :func:`~.step_kernels.symplectic_euler_steps`)."""
        found, layout, arrays = prepared
        system = self.system
        n = system.n
        # the rows (x_p, v_p) of a C-ordered state are read where they are; a state in the system's Fortran
        # order (the first step of a run after a NumPy step or set_state) is copied once: one kernel to compile
        xw = np.ascontiguousarray(X).reshape(n, 2 * system.d)
        sizes = layout.setdefault("sizes", np.empty(len(layout["start"]) - 1))
        return pick(symplectic_euler_steps, len(layout["rows"][3]))(
            layout["start"], layout["lo"], layout["hi"], layout["row0"], xw, layout["fw"],
            *layout["rows"], *arrays, float(found.D), float(found.R), _wind_table(found.winds, ts, system.d),
            layout["other"] if other is None else other, other is not None,
            np.ascontiguousarray(system.m, dtype=np.float64), layout["free"], tuple(found.G.tolist()), hs,
            float(limit), out0, out1, sizes)

    def symplectic_euler(self, X, t, h):
        """One symplectic Euler step from X (n, 2, d) at t by h, compiled; None when it does not apply.

        It does not apply (and the caller takes the NumPy step) when X is not
        the system's state shape, when a spring set does not resolve to the
        numba backend (e.g. ``"auto"`` after particles were removed), when
        the system has more than three spring sets, or, on ``"auto"``, when a
        force has no compiled form (see :meth:`parts`).
        """
        prepared = self._prepared(X)
        if prepared is None:
            return None
        other = self._other(prepared[0], prepared[1], X, t)
        out = self._new_state(X.shape)
        self._steps(prepared, X, np.array([t], dtype=float), np.array([h], dtype=float), other, np.inf, out, out)
        return out

    def symplectic_euler_steps(self, X, times, limit):
        """The symplectic Euler steps from X at ``times[0]`` to ``times[-1]`` in one compiled call, guarded.

        Step k goes from ``times[k]`` to ``times[k + 1]``. After each step
        the largest ``|entry|`` of the new state is compared with `limit`
        (the divergence guard of :func:`particles.integrators.integrate`),
        and the steps stop after the first state that is larger or not
        finite. No Python runs between the steps, so this applies only when
        every force runs inside the kernel: not with clamps or forces without
        a compiled form (then, and where :meth:`symplectic_euler` does not
        apply, it returns None and the caller takes one step at a time).

        Returns
        -------
        (ndarray, int, float) or None
            The last state that passed (shape (n, 2, d), C order; X itself
            if none did), the number of steps that passed and the size of
            the last state computed.
        """
        prepared = self._prepared(X)
        if prepared is None or prepared[0].clamps or prepared[0].others:
            return None
        times = np.asarray(times, dtype=float)
        out0 = self._new_state(X.shape)
        out1 = self._new_state(X.shape)
        taken, size = self._steps(prepared, X, times[:-1], np.diff(times), None, limit, out0, out1)
        return (X if taken == 0 else out1 if taken % 2 == 0 else out0), int(taken), float(size)


def _joints(bending, start, lo, hi):
    """The joints touching each block (``jb0``, ``joints``) and their particles as unsigned indices.

    Joint t is listed for each block that holds one of its three particles
    (in increasing t within a block); the blocks' windows ``lo``, ``hi`` are
    widened, in place, to hold all three particles of their joints.
    """
    blocks = len(start) - 1
    if bending is None:
        empty = np.zeros(0, dtype=np.uint32)
        return np.zeros(blocks + 1, dtype=np.int64), empty, empty, empty, empty
    ijl = np.stack([bending.i, bending.j, bending.l])  # (3, b)
    b = ijl.shape[1]
    touched = np.unique((np.searchsorted(start, ijl, side="right") - 1) * b + np.arange(b))  # block c, joint t
    block, t = touched // b, touched % b
    np.minimum.at(lo, block, ijl.min(axis=0)[t])
    np.maximum.at(hi, block, ijl.max(axis=0)[t] + 1)
    return (np.searchsorted(block, np.arange(blocks + 1)), t.astype(np.uint32),
            *(np.ascontiguousarray(r, dtype=np.uint32) for r in ijl))


def _wind_table(winds, ts, d):
    """The rows ``s, u, gust, t / period, wavelength, per_mass`` of the winds at each time of ts, shape (K, k, 2 d + 4)."""
    W = np.zeros((len(ts), len(winds), 2 * d + 4))
    for q, wind in enumerate(winds):  # a loop over the few winds
        s = wind.strength
        norm = np.linalg.norm(s)
        W[:, q, :d] = s
        W[:, q, d:2 * d] = s / norm if norm > 0 else 0.0
        W[:, q, 2 * d + GUST] = wind.gust
        W[:, q, 2 * d + PHASE] = ts / wind.period
        W[:, q, 2 * d + WAVELENGTH] = wind.wavelength
        W[:, q, 2 * d + PER_MASS] = float(wind.per_mass)
    return W
