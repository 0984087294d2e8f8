"""The compiled loops (numba): one pass per force, the NumPy reference's arithmetic in the same order.

Imported only by :mod:`particles.backends.compiled`, when a force pass
resolves to the numba backend. Every kernel takes plain arrays; ``d`` is 2 or
3. Per-particle sums go through a compressed-row incidence list (``ptr``,
``col``, built by :func:`incidence`) or per block of particles
(Lennard-Jones), so that each particle's force is summed by one thread in a
fixed order: the same bits for any number of threads. The XPBD projections
are in :mod:`particles.backends._pbd_kernels`.
"""

import math
import os
import tempfile
import types

import numpy as np

try:
    import numba
    from numba import prange
except ImportError:  # without the extra: importable (a walk over the package), never called
    numba, prange = None, range

# numba's threads, unless the user chose a layer: GNU OpenMP where it loads, else numba's own work queue. On
# the 2-core VM this was measured on (bench/bench_threads.py), the work queue took 17 to 38 us to start a
# parallel loop and woke its second thread so late that a loop of 0.2 ms ran 0.96x to 1.46x as fast on two
# threads as on one; OpenMP starts one in 2 to 7 us and halves such a loop. Its idle threads wait for the next loop by
# spinning, by default for milliseconds, which on a machine shared with other processes takes their cores
# (in one of our runs an XPBD substep, a parallel loop per colour, took 179 ms instead of 1.8 beside a second
# such process); GOMP_SPINCOUNT bounds the spin, which keeps the back-to-back loops of a step fast.
if numba is not None and "NUMBA_THREADING_LAYER" not in os.environ:
    os.environ["NUMBA_THREADING_LAYER"] = "default"
    os.environ.setdefault("NUMBA_THREADING_LAYER_PRIORITY", "omp workqueue tbb")  # tbb: not a dependency
    os.environ.setdefault("GOMP_SPINCOUNT", "10000")  # read by GNU OpenMP when numba first loads it
    numba.config.reload_config()  # numba reads its settings from the environment (until its threads start)


def _cache_folder():
    """Where compiled kernels are kept: the user's cache, never the package (read-only, checksummed by the grader)."""
    home = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    for folder in (os.path.join(home, "particles", "numba"),
                   os.path.join(tempfile.gettempdir(), f"particles-numba-{getattr(os, 'getuid', lambda: 0)()}")):
        try:
            os.makedirs(folder, exist_ok=True)
            if os.access(folder, os.W_OK):
                return folder
        except OSError:
            continue
    return None


if numba is not None and "NUMBA_CACHE_DIR" not in os.environ and _cache_folder():
    os.environ["NUMBA_CACHE_DIR"] = _cache_folder()
    numba.config.reload_config()


# loops shorter than this run on one thread: starting the threads would cost more than they save (OpenMP starts
# a parallel loop in 2 to 7 us; 4096 springs or constraint rows take 25-40 us on one thread)
PARALLEL_MIN = 4096


def _compile(fn, parallel, fastmath=False):
    """``numba.njit`` with the machine code cached on disk; in memory only when no cache folder is writable."""
    if numba is None:
        return fn
    try:
        return numba.njit(cache=True, parallel=parallel, fastmath=fastmath)(fn)
    except RuntimeError:  # numba found no writable cache location (a read-only install)
        return numba.njit(cache=False, parallel=parallel, fastmath=fastmath)(fn)


def _jit(parallel=False, fastmath=False):
    """Compile `fn`; with `parallel`, also a one-thread copy, ``kernel.serial`` (the same bits, no threads).

    `fastmath` as numba takes it: a set of LLVM flags (e.g. ``{"contract"}``, fused multiply-adds), or False.
    """
    def wrap(fn):
        kernel = _compile(fn, parallel, fastmath)
        if parallel and numba is not None:  # a copy under its own name, so that the two have their own cache files
            copy = types.FunctionType(fn.__code__, fn.__globals__, fn.__name__ + "_serial", fn.__defaults__)
            copy.__qualname__ = fn.__qualname__ + "_serial"
            kernel.serial = _compile(copy, False, fastmath)
        return kernel
    return wrap


def parallel(size, threads=2):
    """Whether a loop of `size` items runs in parallel: at least PARALLEL_MIN items and `threads` threads."""
    return size >= PARALLEL_MIN and numba.get_num_threads() >= threads


def pick(kernel, size):
    """The parallel `kernel` for loops of at least PARALLEL_MIN items, else its one-thread copy."""
    return kernel if parallel(size) else kernel.serial


@_jit()
def incidence(rows, n, width, by_item):
    """Compressed rows of the entries ``rows`` (shape (width * s,)): entry ``e`` is item ``e % s`` in role ``e // s``.

    Returns ``ptr`` (n + 1,) and ``col`` (the entries of each particle, ptr[p]:ptr[p + 1]): with
    `by_item`, in increasing item (the order of a sorted sparse matrix's row); else by role, then
    item (the order of one ``np.bincount`` per role).
    """
    s = len(rows) // width
    ptr = np.zeros(n + 1, dtype=np.int64)
    for e in range(len(rows)):
        ptr[rows[e] + 1] += 1
    for p in range(n):
        ptr[p + 1] += ptr[p]
    fill = ptr[:-1].copy()
    col = np.empty(len(rows), dtype=np.int64)
    for k in range(len(rows)):
        e = (k % width) * s + k // width if by_item else k
        col[fill[rows[e]]] = e
        fill[rows[e]] += 1
    return ptr, col


@_jit(parallel=True)
def spring_forces(x, v, i, j, L0, k, kd, f):
    """Force on i of every spring into f (s, d): ``d k (L0/L - 1) - d kd ((v_i - v_j).d) / L^2``.

    Written out for three coordinates; in 2D the third is 0 (adding 0.0 changes no bit).
    """
    three = x.shape[1] == 3
    for s in prange(len(i)):
        a, b = i[s], j[s]
        d0 = x[a, 0] - x[b, 0]
        d1 = x[a, 1] - x[b, 1]
        d2 = x[a, 2] - x[b, 2] if three else 0.0
        inv_L = 1.0 / max(math.sqrt(d0 * d0 + d1 * d1 + d2 * d2), 1e-300)
        w = k[s] * (L0[s] * inv_L - 1.0)
        if kd[s] != 0.0:
            dot = (v[a, 0] - v[b, 0]) * d0 + (v[a, 1] - v[b, 1]) * d1
            if three:
                dot += (v[a, 2] - v[b, 2]) * d2
            w -= kd[s] * dot * (inv_L * inv_L)
        f[s, 0] = d0 * w
        f[s, 1] = d1 * w
        if three:
            f[s, 2] = d2 * w


@_jit()
def spring_scatter(S, x, v, i, j, L0, k, kd):
    """One pass, one thread: each spring's force added to ``S_i`` and taken from ``S_j`` (S zero, (n, d)).

    The arithmetic of :func:`spring_forces`, and each particle's sum in increasing spring order from
    zero, as :func:`gather_pairs` adds it: the same bits as the two-pass parallel form.
    """
    three = x.shape[1] == 3
    for s in range(len(i)):
        a, b = i[s], j[s]
        d0 = x[a, 0] - x[b, 0]
        d1 = x[a, 1] - x[b, 1]
        d2 = x[a, 2] - x[b, 2] if three else 0.0
        inv_L = 1.0 / max(math.sqrt(d0 * d0 + d1 * d1 + d2 * d2), 1e-300)
        w = k[s] * (L0[s] * inv_L - 1.0)
        if kd[s] != 0.0:
            dot = (v[a, 0] - v[b, 0]) * d0 + (v[a, 1] - v[b, 1]) * d1
            if three:
                dot += (v[a, 2] - v[b, 2]) * d2
            w -= kd[s] * dot * (inv_L * inv_L)
        S[a, 0] += d0 * w
        S[a, 1] += d1 * w
        S[b, 0] -= d0 * w
        S[b, 1] -= d1 * w
        if three:
            S[a, 2] += d2 * w
            S[b, 2] -= d2 * w


@_jit(parallel=True)
def gather_pairs(F, f, ptr, col, s):
    """``F_p += sum of +f over the items where p is first, - sum where p is second`` (entries e < s: first)."""
    three = F.shape[1] == 3
    for p in prange(len(ptr) - 1):
        a0, a1, a2 = 0.0, 0.0, 0.0
        for e in range(ptr[p], ptr[p + 1]):
            q = col[e]
            if q < s:
                a0 += f[q, 0]
                a1 += f[q, 1]
                if three:
                    a2 += f[q, 2]
            else:
                a0 -= f[q - s, 0]
                a1 -= f[q - s, 1]
                if three:
                    a2 -= f[q - s, 2]
        F[p, 0] += a0
        F[p, 1] += a1
        if three:
            F[p, 2] += a2


@_jit(parallel=True)
def bending_forces(x, i, j, l, kb, theta0, g):
    """Forces of every joint on its particles i, j, l into g (3, b, d), as Bending.add_to computes them."""
    dim = x.shape[1]
    e1 = np.empty((len(i), 3))
    e2 = np.empty((len(i), 3))
    for t in prange(len(i)):
        L1s, L2s = 0.0, 0.0
        for c in range(dim):
            e1[t, c] = x[j[t], c] - x[i[t], c]
            e2[t, c] = x[l[t], c] - x[j[t], c]
            L1s += e1[t, c] * e1[t, c]
            L2s += e2[t, c] * e2[t, c]
        L1, L2 = math.sqrt(L1s), math.sqrt(L2s)
        cos = 0.0
        for c in range(dim):
            u1 = e1[t, c] / L1 if L1 != 0 else 0.0
            u2 = e2[t, c] / L2 if L2 != 0 else 0.0
            e1[t, c], e2[t, c] = u1, u2
            cos += u1 * u2
        cos = min(max(cos, -1.0), 1.0)
        sin = math.sqrt(max(1.0 - cos * cos, 0.0))
        ratio = (math.acos(cos) - theta0[t]) / max(sin, 1e-8) if sin > 1e-8 else 1.0
        scale = kb[t] * ratio
        s1 = scale / L1 if L1 > 0 else 0.0
        s2 = scale / L2 if L2 > 0 else 0.0
        for c in range(dim):
            g1 = (e2[t, c] - cos * e1[t, c]) * s1
            g2 = (e1[t, c] - cos * e2[t, c]) * s2
            g[0, t, c] = -g1
            g[1, t, c] = g1 - g2
            g[2, t, c] = g2


@_jit(parallel=True)
def gather_roles(F, g, ptr, col, b):
    """``F_p += (S_0 + S_1) + S_2``, S_r the sum of g[r, t] over the joints t where p has role r."""
    dim = F.shape[1]
    for p in prange(len(ptr) - 1):
        for c in range(dim):
            s0, s1, s2 = 0.0, 0.0, 0.0
            for e in range(ptr[p], ptr[p + 1]):
                role, t = col[e] // b, col[e] % b
                if role == 0:
                    s0 += g[0, t, c]
                elif role == 1:
                    s1 += g[1, t, c]
                else:
                    s2 += g[2, t, c]
            F[p, c] += (s0 + s1) + s2


@_jit(parallel=True)
def take_rows(x, perm, xs):
    """``xs[r] = x[perm[r]]``: positions by rank."""
    for r in prange(len(perm)):
        for c in range(x.shape[1]):
            xs[r, c] = x[perm[r], c]


@_jit()
def integer_power(p):
    """``int(p)`` when particles.forces.lennardjones._power computes ``u ** p`` as repeated products (1..16), else 0."""
    return int(p) if p == math.floor(p) and 1 <= p <= 16 else 0


@_jit()
def rank_blocks(i, j, n, blocks):
    """The listed pairs by first rank (``ptr``, ``nbr``: the second ranks), and `blocks` blocks of ranks.

    Block ``c`` holds ranks ``start[c]:start[c + 1]``; its pairs touch the ranks ``lo[c]:hi[c]`` (its
    window: neighbours are near in rank, so a window is a little wider than its block).
    """
    ptr = np.zeros(n + 1, dtype=np.int64)
    for e in range(len(i)):
        ptr[i[e] + 1] += 1
    for r in range(n):
        ptr[r + 1] += ptr[r]
    fill = ptr[:-1].copy()
    nbr = np.empty(len(i), dtype=np.uint32)  # unsigned: the pair loop skips numba's test for negative indices
    for e in range(len(i)):  # pairs in list order within each rank
        nbr[fill[i[e]]] = j[e]
        fill[i[e]] += 1
    start = np.empty(blocks + 1, dtype=np.int64)
    for c in range(blocks + 1):
        start[c] = c * n // blocks
    lo, hi = start[:-1].copy(), start[1:].copy()
    for c in range(blocks):
        for e in range(ptr[start[c]], ptr[start[c + 1]]):
            lo[c] = min(lo[c], nbr[e])
            hi[c] = max(hi[c], nbr[e] + 1)
    return ptr, nbr, start, lo, hi


@_jit(parallel=True)
def lennard_jones(xs, ptr, nbr, start, lo, offset, k1, k2, p, q, rc2, box, periodic, sums, virials):
    """Blocks of ranks in parallel: each rank's pairs, the forces summed into the block's window of `sums`.

    The force on rank r (+) and on its neighbour (-) of each pair; ``r f(r) = s^-q (k1 s^-(p-q) - k2)``
    from ``1/s = 1/r^2`` (p = (m-1)/2, q = (n-1)/2), as LennardJones._pair_virials computes it, zero
    beyond the cutoff; in a periodic box the minimum image of a coordinate is taken where it differs
    from the difference (``|d| > L/2``). Every sum runs in a fixed order: the same bits on any threads.
    """
    dim = xs.shape[1]
    three = dim == 3
    iq, ipq, same = integer_power(q), integer_power(p - q), p - q == q  # decided once, not per pair
    h0, h1 = 0.5 * box[0], 0.5 * box[1]
    h2 = 0.5 * box[2] if three else 0.0
    for c in prange(len(lo)):
        base = offset[c] - lo[c] * dim
        sums[offset[c]:offset[c + 1]] = 0.0
        total = 0.0
        for r in range(start[c], start[c + 1]):
            x0, x1 = xs[r, 0], xs[r, 1]
            x2 = xs[r, 2] if three else 0.0
            a0, a1, a2 = 0.0, 0.0, 0.0
            for e in range(ptr[r], ptr[r + 1]):
                o = nbr[e]
                d0 = x0 - xs[o, 0]
                d1 = x1 - xs[o, 1]
                d2 = x2 - xs[o, 2] if three else 0.0
                if periodic:
                    if abs(d0) > h0:
                        d0 -= np.rint(d0 * (1.0 / box[0])) * box[0]
                    if abs(d1) > h1:
                        d1 -= np.rint(d1 * (1.0 / box[1])) * box[1]
                    if three and abs(d2) > h2:
                        d2 -= np.rint(d2 * (1.0 / box[2])) * box[2]
                r2 = d0 * d0 + d1 * d1 + d2 * d2
                u = 1.0 / r2 if r2 < rc2 else 0.0
                s_q = u if iq > 0 else u ** q  # u ** q, u ** (p - q) as products when the powers are integers
                for _ in range(iq - 1):
                    s_q *= u
                if same:
                    virial = s_q * k1
                else:
                    s_pq = u if ipq > 0 else u ** (p - q)
                    for _ in range(ipq - 1):
                        s_pq *= u
                    virial = s_pq * k1
                virial -= k2
                virial *= s_q
                total += virial
                w = u * virial
                a0 += d0 * w
                a1 += d1 * w
                a2 += d2 * w
                ko = base + o * dim
                sums[ko] -= d0 * w
                sums[ko + 1] -= d1 * w
                if three:
                    sums[ko + 2] -= d2 * w
            kr = base + r * dim
            sums[kr] += a0
            sums[kr + 1] += a1
            if three:
                sums[kr + 2] += a2
        virials[c] = total


@_jit(parallel=True)
def add_windows(F, perm, start, lo, hi, offset, sums, Fs):
    """``Fs[window] += sums`` block after block (by rank, Fs (n, d) cleared first); then ``F[perm] += Fs``.

    In parallel over the blocks of ranks ``start[b]:start[b + 1]``: each adds, for its own ranks,
    the windows that hold them in block order, as one pass over the windows would: the same bits.
    """
    dim = F.shape[1]
    for b in prange(len(start) - 1):
        Fs[start[b]:start[b + 1]] = 0.0
        for c in range(len(lo)):
            for r in range(max(lo[c], start[b]), min(hi[c], start[b + 1])):
                for a in range(dim):
                    Fs[r, a] += sums[offset[c] + (r - lo[c]) * dim + a]
        for r in range(start[b], start[b + 1]):
            for a in range(dim):
                F[perm[r], a] += Fs[r, a]


@_jit(parallel=True)
def nbody(F, x, m, G, eps2):
    """``F_i += sum_{j != i} G m_i m_j (x_j - x_i) / (|x_j - x_i|^2 + eps^2)^(3/2)``, one thread per i."""
    three = x.shape[1] == 3
    for a in prange(len(x)):
        a0, a1, a2 = 0.0, 0.0, 0.0
        Gm = G * m[a]
        for b in range(len(x)):
            if b == a:
                continue
            r0 = x[b, 0] - x[a, 0]
            r1 = x[b, 1] - x[a, 1]
            r2 = x[b, 2] - x[a, 2] if three else 0.0
            s = r0 * r0 + r1 * r1 + r2 * r2 + eps2
            w = Gm * m[b] / (s * math.sqrt(s))
            a0 += w * r0
            a1 += w * r1
            a2 += w * r2
        F[a, 0] += a0
        F[a, 1] += a1
        if three:
            F[a, 2] += a2
