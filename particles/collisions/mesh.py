"""Triangle meshes: the connectivity of a cloth seen as a surface, not as particles.

A particle cloth can pass through itself between its particles: two
triangles cross while every pair of particles stays apart. To see (and
prevent) that, the cloth is a *triangle mesh*: the particles are its vertices
and a list of faces, three vertex indices each, tells which triples span a
piece of the surface. :class:`TriangleMesh` stores that connectivity only;
positions stay in the state ``X`` of the system, so one mesh serves every
step.

1. **Faces** ``faces[f] = (i, j, k)``: the triangle with vertices ``x[i]``,
   ``x[j]``, ``x[k]``; its normal ``(x_j - x_i) x (x_k - x_i)`` follows the
   right-hand rule.
2. **Edges**: every unordered pair of vertices that are consecutive in some
   face, once, as ``(i, j)`` with ``i < j``, sorted. An edge is found from its
   integer key ``i n + j`` (one ``np.unique`` over the ``3 m`` face edges).
3. **Face edges** ``face_edges[f] = (e0, e1, e2)``: the edges ``(v0, v1)``,
   ``(v1, v2)``, ``(v2, v0)`` of face ``f``, as indices into ``edges``.
4. **Adjacency**: two faces that share a vertex touch by construction; the
   intersection test of :mod:`particles.collisions.triangle_crossing` and the collision
   tests skip them.

:meth:`TriangleMesh.grid` triangulates the grid of
:func:`particles.massspring.cloth.cloth`: particle ``(i, j)`` (column ``i``, row ``j``) is
vertex ``j nx + i``, and each grid cell is cut along its diagonal
``(i, j)-(i+1, j+1)`` into two triangles.

References
----------
.. [1] R. Bridson, R. Fedkiw and J. Anderson, "Robust treatment of collisions,
   contact and friction for cloth animation", ACM Transactions on Graphics
   21(3) (SIGGRAPH 2002), 594-603 (the cloth as a triangle mesh: vertex-face
   and edge-edge pairs).
.. [2] M. Botsch, L. Kobbelt, M. Pauly, P. Alliez and B. Levy, *Polygon Mesh
   Processing*, A K Peters, 2010, chapter 2 (face-vertex mesh data structures).
"""

import numpy as np

from .._checks import count

__all__ = ["TriangleMesh"]


class TriangleMesh:
    """Connectivity of a triangle mesh: faces over ``n`` vertices (no positions).

    Parameters
    ----------
    faces : array_like of int, shape (m, 3)
        Vertex indices of each triangle, in [0, n), three different ones per face.
    n : int, optional
        Number of vertices (default: ``faces.max() + 1``). Vertices that are in
        no face are allowed (a pinned particle, a loose thread).

    Attributes
    ----------
    faces : ndarray of int64, shape (m, 3)
    n : int
    edges : ndarray of int64, shape (e, 2)
        Unique edges, ``edges[:, 0] < edges[:, 1]``, sorted lexicographically.
    face_edges : ndarray of int64, shape (m, 3)
        Index into `edges` of the edges ``(v0, v1)``, ``(v1, v2)``, ``(v2, v0)`` of each face.

    Examples
    --------
    Two triangles of a unit square:

    >>> mesh = TriangleMesh([[0, 1, 3], [0, 3, 2]])
    >>> mesh.n, mesh.edges.tolist()
    (4, [[0, 1], [0, 2], [0, 3], [1, 3], [2, 3]])
    >>> mesh.face_edges.tolist()
    [[0, 3, 2], [2, 4, 1]]
    """

    def __init__(self, faces, n=None):
        f = np.asarray(faces)
        if f.size == 0 and f.ndim <= 2:
            f = np.zeros((0, 3), dtype=np.int64)
        if f.ndim != 2 or f.shape[1] != 3 or not np.issubdtype(f.dtype, np.integer):
            raise ValueError(f"faces must be an integer array of shape (m, 3), got {f.dtype} {f.shape}")
        f = f.astype(np.int64)
        if n is None:
            n = int(f.max()) + 1 if len(f) else 0
        self.n = count(n, "n", 0)
        if len(f) and (f.min() < 0 or f.max() >= self.n):
            raise ValueError(f"faces must hold vertex indices in [0, {self.n}), got indices from "
                             f"{int(f.min())} to {int(f.max())}")
        repeated = (f[:, 0] == f[:, 1]) | (f[:, 1] == f[:, 2]) | (f[:, 2] == f[:, 0])
        if repeated.any():
            bad = int(np.flatnonzero(repeated)[0])
            raise ValueError(f"faces must have three different vertices, but face {bad} is {f[bad].tolist()}")
        self.faces = f
        self.faces.setflags(write=False)
        a = f.ravel()
        b = f[:, [1, 2, 0]].ravel()
        keys = np.minimum(a, b) * max(self.n, 1) + np.maximum(a, b)  # one integer per edge
        unique, inverse = np.unique(keys, return_inverse=True)
        self.edges = np.stack(np.divmod(unique, max(self.n, 1)), axis=1).astype(np.int64)
        self.face_edges = inverse.reshape(-1, 3).astype(np.int64)
        self.edges.setflags(write=False)
        self.face_edges.setflags(write=False)

    @classmethod
    def grid(cls, nx, ny):
        """The triangulated grid of :func:`particles.massspring.cloth.cloth` (``nx`` columns, ``ny`` rows).

        Particle ``(i, j)`` is vertex ``j nx + i``. The cell with corners
        ``a = (i, j)``, ``b = (i+1, j)``, ``c = (i, j+1)``, ``d = (i+1, j+1)``
        gives the triangles ``(a, b, d)`` and ``(a, d, c)``, both counter-clockwise
        in the (column, row) plane. Faces are ordered by cell (row by row), the
        two triangles of a cell consecutive: ``2 (nx - 1) (ny - 1)`` faces.

        Examples
        --------
        >>> TriangleMesh.grid(3, 2).faces.tolist()
        [[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4]]
        """
        nx, ny = count(nx, "nx", 2), count(ny, "ny", 2)
        idx = np.arange(nx * ny, dtype=np.int64).reshape(ny, nx)
        a, b = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel()
        c, d = idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
        faces = np.stack([np.stack([a, b, d], axis=1), np.stack([a, d, c], axis=1)], axis=1).reshape(-1, 3)
        return cls(faces, nx * ny)

    @property
    def m(self):
        """Number of faces."""
        return len(self.faces)

    def share_vertex(self, fa, fb):
        """Whether faces ``fa[k]`` and ``fb[k]`` have a vertex in common (a face shares all with itself).

        Parameters
        ----------
        fa, fb : array_like of int, shape (p,)
            Face indices, in [0, m).

        Returns
        -------
        ndarray of bool, shape (p,)
        """
        fa, fb = self._face_indices(fa, "fa"), self._face_indices(fb, "fb")
        if fa.shape != fb.shape:
            raise ValueError(f"fa and fb must have the same shape, got {fa.shape} and {fb.shape}")
        A, B = self.faces[fa], self.faces[fb]
        return (A[:, :, None] == B[:, None, :]).any(axis=(1, 2))

    def _face_indices(self, f, name):
        f = np.asarray(f)
        if f.size == 0:
            return np.zeros(0, dtype=np.int64)
        if f.ndim != 1 or not np.issubdtype(f.dtype, np.integer):
            raise ValueError(f"{name} must be a 1D integer array of face indices, got {f.dtype} {f.shape}")
        if f.min() < 0 or f.max() >= self.m:
            raise ValueError(f"{name} must hold face indices in [0, {self.m}), got {f.min()} to {f.max()}")
        return f

    def __repr__(self):
        return f"TriangleMesh(n={self.n}, faces={self.m}, edges={len(self.edges)})"
