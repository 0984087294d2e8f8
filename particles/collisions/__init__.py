"""Collisions: particles against implicit surfaces, and cloth meshes against themselves and moving bodies.

Particles (:class:`Collider`) and cloth (:class:`ClothCollisions`, :class:`SelfCollision`) share the
surfaces; the cloth pipeline of Bridson, Fedkiw and Anderson is built from the mesh, the closest points,
the continuous test and the broad phase (``from particles.collisions import Collider, Plane``).

* :mod:`particles.collisions.surfaces`: implicit surfaces (:class:`Plane`, :class:`Sphere`, :class:`Box`,
  :class:`Cylinder`, unions, intersections, complements);
* :mod:`particles.collisions.moving`: surfaces that move (:class:`MovingSurface`, :class:`RigidlyMoved`);
* :mod:`particles.collisions.surface_crossing`: where a particle's path within a step crosses a surface
  (Hermite paths);
* :mod:`particles.collisions.response`: the formulas of a contact: the normal and friction changes of a
  particle on a surface (:func:`respond`), the proximity impulse of two cloth pieces;
* :mod:`particles.collisions.collider`: :class:`Collider`, particles bouncing off surfaces, with friction and
  resting contact;
* :mod:`particles.collisions.collider_kernels`: the collider compiled, particle by particle, on primitive
  surfaces;
* :mod:`particles.collisions.mesh`: :class:`TriangleMesh`, the cloth's faces and edges;
* :mod:`particles.collisions.triangle_crossing`: triangle-triangle intersection tests and the boxes' bucket
  grid (:func:`box_pairs`, :func:`intervals_overlap`);
* :mod:`particles.collisions.proximity`: closest points of vertex-triangle and edge-edge pairs;
* :mod:`particles.collisions.ccd`: continuous collision detection: when, within a step, a vertex hits a
  triangle or two edges meet;
* :mod:`particles.collisions.candidates`: the broad phase: pairs whose swept boxes overlap;
* :mod:`particles.collisions.candidate_cache`: the pairs kept from step to step
  (:class:`~particles.collisions.candidate_cache.CandidateCache`), and the loader of the compiled stages;
* :mod:`particles.collisions.bodies`: the cloth against moving bodies (stage 1 of the pipeline);
* :mod:`particles.collisions.proximity_impulses`: impulses between pieces of the cloth closer than its
  thickness (stage 2 of the pipeline);
* :mod:`particles.collisions.strain_limit`: stretch springs held within Provot's limit inside the treatment,
  alternating with the bodies and closed by the continuous test (stage 2b of the pipeline);
* :mod:`particles.collisions.zones`: impact zones, moved rigidly (stage 4 of the pipeline);
* :mod:`particles.collisions.pipeline`: :class:`ClothCollisions`, the Bridson-Fedkiw-Anderson stages applied
  after each step;
* :mod:`particles.collisions.compiled_stages`: the pipeline's stages compiled (the same contacts and verdicts),
  over their kernels: :mod:`particles.collisions.broad_kernels` (the broad phase),
  :mod:`particles.collisions.contact_kernels` (closest points, proximity tests, the continuous test),
  :mod:`particles.collisions.impulse_kernels` (the proximity impulses' Jacobi iterations),
  :mod:`particles.collisions.body_kernels` (the cloth against bodies at rest);
* :mod:`particles.collisions.selfcollision`: :class:`SelfCollision`, a mass-spring cloth's particles kept a
  thickness apart;
* :mod:`particles.collisions.resting`: :class:`BallContacts`, balls resting on a surface and on each other (a
  stack) without chatter: collisions bounce, resting contacts are only closed.
"""

from .ccd import BISECTIONS, F_TOL, Impacts, coplanarity_cubic, cubic_roots, detect, first_contact, overlapping
from .collider import Collider, Contacts
from .mesh import TriangleMesh
from .moving import MovingSurface, RigidlyMoved, rotation_matrix
from .pipeline import ClothCollisionResult, ClothCollisions
from .proximity import PARALLEL, Closest, edge_edge, point_segment, vertex_face
from .response import respond
from .resting import BallContacts, ContactImpulses
from .selfcollision import SelfCollision, SelfCollisionResult
from .surface_crossing import cubic_path, first_crossing, hermite, hermite_coefficients, path_speed
from .surfaces import Box, Complement, Cylinder, Intersection, Plane, Sphere, Surface, Union
from .triangle_crossing import box_pairs, intersections, intervals_overlap, orientation

__all__ = ["Surface", "Plane", "Sphere", "Box", "Cylinder", "Union", "Intersection", "Complement", "MovingSurface",
           "RigidlyMoved", "rotation_matrix", "hermite", "hermite_coefficients", "cubic_path", "path_speed",
           "first_crossing", "respond", "Contacts", "Collider", "TriangleMesh", "intersections", "box_pairs",
           "orientation", "intervals_overlap", "Closest", "point_segment", "vertex_face", "edge_edge", "PARALLEL", "cubic_roots",
           "coplanarity_cubic", "Impacts", "overlapping", "first_contact", "detect", "BISECTIONS", "F_TOL",
           "ClothCollisions", "ClothCollisionResult", "SelfCollision", "SelfCollisionResult", "BallContacts",
           "ContactImpulses"]
