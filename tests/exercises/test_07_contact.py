"""Autograder tests of exercise 07_contact: the contact response, projection onto an implicit surface, the
overshooting problem of a bouncing ball, and resting contact on an incline with friction.

Public tests use the notebook's contacts, ball, floor and incline, whose answers a student can work out or read
in the notebook; hidden tests draw velocities, normals, restitutions, friction coefficients, resting speeds,
surfaces (planes, balls, containers, boxes), steps and inclines from the grading seed (fixture ``rng``) and never
print them (``show_values=False``).

Every expected value comes from the reference library, computed here in the grader: the response of
``particles.collisions.respond`` (with no restitution for the contacts a resting speed marks as resting), the
surfaces' signed distances and normals, the library's ``Collider`` for a step of the ball (``collide`` with
``"project"`` or ``"backtrack"``: backtracking along the step's exact path under constant gravity), and the
incline's loop of the notebook run with ``respond``. The physics is checked too: a backtracked ball keeps
``eps^2`` of its apex per bounce, a particle below the friction angle does not move at all, one above slides by
exactly Coulomb's law for the steps taken.

Typical mistakes are named from the wrong answers they produce: the normal velocity not reversed, restitution on
the whole velocity or applied twice, friction that reverses the motion or is bounded without the ``1 + eps``,
separating particles responded, resting contacts that bounce; a projection along ``+H n`` or of particles outside;
a bounce responded with the velocity of the start or the end of the step, or left on the floor; an apex without
``v^2 / (2 g)``; an incline that chatters (no resting contact) or creeps (the response after the move).
"""

import numpy as np
import pytest

from particles.collisions import Box, Collider, Plane, Sphere, respond
from particles.course.grading.expect import expect_array, expect_float
from particles.course.grading.memo import memoized
from particles.course.worker.runner import GradingFailure

EXERCISE = "07_contact"
_WRITE = "write the response and the fixes of the overshooting problem yourself"
FORBIDDEN = {
    "particles.collisions.respond": "it is the response you are asked to write",
    "particles.collisions.Collider": f"it collides particles for you; {_WRITE}",
    "particles.collisions.first_crossing": "find the time of the contact yourself",
    "particles.studies.bounce": "it runs the bouncing ball you are asked to simulate",
}

G = 9.81
UP = np.array([[0.0, 1.0]])
V0 = -0.25  # the ball's velocity at its start, 1 m above the floor (m/s)


# -- the response --------------------------------------------------------------------------------


def _response(v, n, eps, mu, v_rest=0.0, variant=None):
    """The library's response; with v_rest, contacts approaching no faster get no restitution."""
    v, n = np.asarray(v, dtype=float), np.asarray(n, dtype=float)
    if variant is not None:
        return _wrong_response(v, n, eps, mu, v_rest, variant)
    vn = np.sum(v * n, axis=1)
    resting = (vn < 0) & (-vn <= v_rest)
    bounce, rest = respond(v, n, eps, mu)[0], respond(v, n, 0.0, mu)[0]
    return np.where(resting[:, None], rest, bounce)


def _wrong_response(v, n, eps, mu, v_rest, variant):
    """A response with one typical mistake (for the hints)."""
    vn = np.sum(v * n, axis=1)
    v_n, v_t = vn[:, None] * n, v - vn[:, None] * n
    slow = np.abs(vn) <= v_rest if variant == "separating responded" else (vn < 0) & (-vn <= v_rest)
    e = np.where(slow & (variant != "resting bounces"), 0.0, eps)[:, None]
    approaching = (vn < 0)[:, None] | (variant == "separating responded")
    normal = {"not reversed": e * v_n, "twice": -e * e * v_n}.get(variant, -e * v_n)
    impulse = (1 + e) * np.abs(vn)[:, None] if variant != "friction without 1 + eps" else np.abs(vn)[:, None]
    speed = np.linalg.norm(v_t, axis=1)[:, None]
    removed = mu * impulse if variant == "friction reverses" else np.minimum(mu * impulse, speed)
    tangential = v_t - removed * np.divide(v_t, speed, out=np.zeros_like(v_t), where=speed > 0)
    if variant == "whole velocity":
        tangential = e * tangential
    if variant == "friction when separating":  # the normal part right, friction from (1 + e) |v . n| on every row
        e_all = np.where(-vn <= v_rest, 0.0, eps)[:, None]
        removed = np.minimum(mu * (1 + e_all) * np.abs(vn)[:, None], speed)
        friction = removed * np.divide(v_t, speed, out=np.zeros_like(v_t), where=speed > 0)
        return np.where((vn < 0)[:, None], -e * v_n, v_n) + v_t - friction
    return np.where(approaching, tangential + normal, v)


_RESPONSE_HINTS = (
    ("v_t + eps v_n: the normal part is not reversed (the particle goes on into the solid); the response is "
     "v_t - eps v_n", "not reversed"),
    ("restitution on the whole velocity: only the normal part is scaled by eps, the tangential part changes only "
     "by friction", "whole velocity"),
    ("restitution applied twice (-eps^2 v_n): the normal part becomes -eps v_n once", "twice"),
    ("friction that reverses the tangential velocity: it removes at most |v_t| and never pushes the particle "
     "backwards", "friction reverses"),
    ("friction bounded by mu |v . n|: the tangential impulse is at most mu times the normal one, mu (1 + eps) "
     "|v . n|", "friction without 1 + eps"),
    ("separating particles responded too: a particle with v . n >= 0 already moves away and keeps its velocity",
     "separating responded"),
    ("resting contacts that bounce: a contact with |v . n| <= v_rest gets no restitution (eps = 0)",
     "resting bounces"),
    ("friction on separating particles too: a particle moving away (v . n >= 0) gets no impulse, along the normal "
     "or across it", "friction when separating"),
)


def _response_hints(v, n, eps, mu, v_rest):
    return lambda: {label: _response(v, n, eps, mu, v_rest, variant) for label, variant in _RESPONSE_HINTS}


def _check_response(student, v, n, eps, mu, v_rest, call, hidden):
    got = student.call("contact_response", v, n, eps, mu, v_rest, check_inputs=True)
    expect_array(got, _response(v, n, eps, mu, v_rest), call, rtol=1e-9, atol=1e-12,
                 hints=_response_hints(v, n, eps, mu, v_rest), show_values=not hidden)


@pytest.mark.points(2)
def test_contact_response_by_hand(student):
    """contact_response on the floor: a bounce, a bounce with friction, a slider stopped, a separating particle."""
    v = np.array([[3.0, -4.0], [0.5, -4.0], [1.0, 2.0], [2.0, -0.05]])
    n = np.repeat(UP, 4, axis=0)
    _check_response(student, v, n, 0.5, 0.2, 0.1, "contact_response(v=[[3, -4], [0.5, -4], [1, 2], [2, -0.05]], "
                    "n = (0, 1) each, eps=0.5, mu=0.2, v_rest=0.1)", False)
    _check_response(student, v[:1], n[:1], 0.5, 0.0, 0.0, "contact_response(v=[[3, -4]], n=[[0, 1]], eps=0.5, "
                    "mu=0, v_rest=0)", False)


@pytest.mark.points(3)
@pytest.mark.hidden
def test_contact_response_random(student, rng):
    """contact_response matches the library's response on random contacts in 2D and 3D, some resting, some leaving."""
    for d in (2, 3):
        k = int(rng.integers(5, 12))
        n = rng.normal(size=(k, d))
        n /= np.linalg.norm(n, axis=1)[:, None]
        v = rng.normal(0.0, 2.0, (k, d))
        v_rest = float(rng.uniform(0.2, 1.0))
        slow = rng.random(k) < 0.3                        # some contacts slower than v_rest
        v[slow] += (-0.5 * v_rest - np.sum(v[slow] * n[slow], axis=1))[:, None] * n[slow]
        _check_response(student, v, n, float(rng.uniform(0.1, 1.0)), float(rng.uniform(0.0, 1.0)), v_rest,
                        f"contact_response on {k} random contacts in {d}D", True)


# -- collide -------------------------------------------------------------------------------------


def _check_collide(student, surface, x, v, eps, mu, v_rest, call, hidden):
    H, n = surface.H(x), surface.normal(x)
    got = student.call("collide", x, v, H, n, eps, mu, v_rest, check_inputs=True)
    if not isinstance(got, tuple) or len(got) != 2:
        raise GradingFailure(f"{call} returned {type(got).__name__}, expected the pair (x_new, v_new)")
    inside = H < 0
    x_ref, v_ref = x.copy(), v.copy()
    x_ref[inside] = x[inside] - H[inside, None] * n[inside]
    v_ref[inside] = _response(v[inside], n[inside], eps, mu, v_rest)
    x_out = x.copy()
    x_out[inside] = x[inside] + H[inside, None] * n[inside]
    expect_array(got[0], x_ref, f"x_new of {call}", rtol=1e-12, atol=1e-12, show_values=not hidden, hints={
        "x + H n: the particles moved further into the solid; the closest surface point is x - H n": x_out,
        "every particle projected onto the surface, those outside too: only H < 0 is a collision":
            x - H[:, None] * n,
        "the positions left unchanged: a particle inside goes to the surface, x - H n": x})
    expect_array(got[1], v_ref, f"v_new of {call}", rtol=1e-9, atol=1e-12, show_values=not hidden, hints={
        "the velocities left unchanged: a projected particle gets the response of section 1": v,
        "every particle responded, those outside too: only H < 0 is a collision":
            _response(v, n, eps, mu, v_rest)})


@pytest.mark.points(1)
def test_collide_ball(student):
    """collide puts the notebook's three particles inside the ball on its surface and responds; two stay as they were."""
    x = np.array([[0.5, 0.0], [0.0, -0.9], [0.3, 0.4], [1.5, 0.0], [0.0, 2.0]])
    _check_collide(student, Sphere([0.0, 0.0], 1.0), x, -x, 1.0, 0.0, 0.0,
                   "collide of five particles moving to the centre of the unit ball, eps=1", False)


@pytest.mark.points(2)
@pytest.mark.hidden
def test_collide_random_surfaces(student, rng):
    """collide projects onto random planes, balls, containers and boxes (x - H n) and responds, in 2D."""
    surfaces = [Plane(rng.normal(size=2), rng.normal(size=2)), Sphere(rng.normal(size=2), rng.uniform(0.5, 2.0)),
                Sphere([0.0, 0.0], rng.uniform(1.0, 2.0), container=True), Box([-1.0, -0.5], [0.8, 1.2])]
    for surface in surfaces:
        x = rng.uniform(-2.5, 2.5, (int(rng.integers(6, 15)), 2))
        v = rng.normal(0.0, 2.0, x.shape)
        _check_collide(student, surface, x, v, float(rng.uniform(0.0, 1.0)), float(rng.uniform(0.0, 0.8)),
                       float(rng.uniform(0.0, 0.5)), f"collide with a random {type(surface).__name__.lower()}", True)


# -- bounce_step ---------------------------------------------------------------------------------


def _library_step(y, v, h, eps, method):
    """One step of the ball with the library's collider: (y, v, touched)."""
    floor = Collider(Plane([0.0, 0.0], [0.0, 1.0]), restitution=eps, method=method)
    X_old = np.array([[[0.0, y], [0.0, v]]])
    X_new = np.array([[[0.0, y + h * v - G * h * h / 2], [0.0, v - G * h]]])  # exact under constant gravity
    X, contacts = floor.collide(X_old, X_new, 0.0, h)
    return float(X[0, 0, 1]), float(X[0, 1, 1]), bool(len(contacts.time))


def _wrong_step(y, v, h, eps, variant):
    """A backtracked step with one typical mistake (for the hints), as (y, v)."""
    y1, v1 = y + h * v - G * h * h / 2, v - G * h
    tau = (v + np.sqrt(v * v + 2 * G * y)) / G
    hit = {"start velocity": v, "end velocity": v1}.get(variant, v - G * tau)
    up = -eps * hit
    r = h - tau
    if variant == "left on the floor":
        return 0.0, up
    if variant == "old velocity after":
        return up * r - G * r * r / 2, v1
    return up * r - G * r * r / 2, up - G * r


def _numbers(values, call):
    """The floats a student's function returned, or a GradingFailure saying what came back."""
    try:
        return np.array([float(value) for value in values])
    except (TypeError, ValueError):
        raise GradingFailure(f"{call} are not numbers: {', '.join(type(v).__name__ for v in values)}") from None


def _check_step(student, y, v, h, eps, method, call, hidden):
    got = student.call("bounce_step", y, v, h, eps, method)
    if not isinstance(got, tuple) or len(got) != 3:
        raise GradingFailure(f"{call} returned {type(got).__name__}, expected (y, v, touched)")
    y_ref, v_ref, touched = _library_step(y, v, h, eps, method)
    if bool(got[2]) != touched:
        raise GradingFailure(f"{call} says touched={got[2]!r}; the ball {'did' if touched else 'did not'} go below "
                             "the floor in this step")
    hints = {}
    if method == "backtrack" and touched:
        for label, variant in (
                ("a response to the velocity of the start of the step: respond to the velocity at the moment of "
                 "contact, v0 - g tau", "start velocity"),
                ("a response to the velocity of the end of the step, as projection does: backtracking responds "
                 "to the velocity at the moment of contact", "end velocity"),
                ("the ball left on the floor with the new velocity: fly the rest of the step from the floor",
                 "left on the floor"),
                ("the rest of the step flown, but the velocity returned is the one before the contact",
                 "old velocity after")):
            hints[label] = np.array(_wrong_step(y, v, h, eps, variant))
    expect_array(_numbers(got[:2], f"(y, v) of {call}"), np.array([y_ref, v_ref]), f"(y, v) of {call}", rtol=1e-9,
                 atol=1e-12, hints=hints, show_values=not hidden)


@pytest.mark.points(2)
@pytest.mark.parametrize("method", ["project", "backtrack"])
def test_bounce_step_by_hand(student, method):
    """bounce_step of a ball 5 cm above the floor at -2 m/s over 50 ms: it lands in the step; and a step without contact."""
    _check_step(student, 0.05, -2.0, 0.05, 0.8, method, f"bounce_step(y=0.05, v=-2, h=0.05, eps=0.8, {method!r})",
                False)
    _check_step(student, 0.5, -2.0, 0.05, 0.8, method, f"bounce_step(y=0.5, v=-2, h=0.05, eps=0.8, {method!r})",
                False)


@pytest.mark.points(2)
@pytest.mark.hidden
def test_bounce_step_random(student, rng):
    """bounce_step matches the library's collider on random steps that cross the floor, both fixes."""
    for method in ("project", "backtrack", "backtrack"):
        h, v = rng.uniform(0.005, 0.03), -rng.uniform(1.0, 5.0)  # one contact per step: the ball leaves the floor
        y = rng.uniform(0.05, 0.95) * (-v * h + G * h * h / 2)  # above the floor, below it at the end
        _check_step(student, y, v, h, float(rng.uniform(0.5, 1.0)), method,
                    f"bounce_step({method!r}) of a random step that crosses the floor", True)


# -- bounce_heights ------------------------------------------------------------------------------


@memoized
def _reference_apexes(method, eps, h, bounces):
    """The apexes with the library's collider, step by step, and whether a step ended within 1e-9 m of the floor."""
    floor = Collider(Plane([0.0, 0.0], [0.0, 1.0]), restitution=eps, method=method)
    X = np.array([[[0.0, 1.0], [0.0, V0]]])
    apex, close = [1.0 + V0 * V0 / (2 * G)], False
    while len(apex) <= bounces:  # a loop over time steps
        y, v = X[0, 0, 1], X[0, 1, 1]
        X_new = np.array([[[0.0, y + h * v - G * h * h / 2], [0.0, v - G * h]]])
        close |= abs(X_new[0, 0, 1]) < 1e-9
        X, contacts = floor.collide(X, X_new, 0.0, h)
        if len(contacts.time):
            apex.append(X[0, 0, 1] + X[0, 1, 1] ** 2 / (2 * G))
    return np.array(apex), close


def _check_apexes(student, feedback, method, eps, h, bounces, call, hidden):
    expected, _ = _reference_apexes(method, eps, h, bounces)
    got = student.call("bounce_heights", method, eps, h, bounces)
    if isinstance(got, np.ndarray) and got.shape == expected.shape:
        feedback.curve(f"Apex of each bounce, {method}", "bounce", "apex (m)",
                       [{"label": "yours", "x": np.arange(len(got)), "y": got},
                        {"label": "reference", "x": np.arange(len(got)), "y": expected}], loglog=False)
    expect_array(got, expected, call, rtol=1e-7, atol=1e-12, show_values=not hidden, hints={
        "the first apex missing: the array starts with the apex of the start, 1 + 0.25^2 / (2 g) m": expected[1:],
        "your result matches y alone: the apex is y + v^2 / (2 g), the height the flight will reach":
            lambda got: _matches_heights_only(got, expected)})
    if method == "backtrack":
        ratios = got[1:] / got[:-1]
        if not np.allclose(ratios, eps**2, rtol=1e-7):
            raise GradingFailure(f"{call}: the apexes of a backtracked ball must fall by eps^2 per bounce")


def _matches_heights_only(got, expected):
    """Whether every apex after the first is far below the reference (a height at the end of a step, not its apex)."""
    return bool(np.all(got[1:] < 0.5 * expected[1:]))


@pytest.mark.points(2)
def test_bounce_heights_backtrack(student, feedback):
    """bounce_heights('backtrack', 0.8, 10 ms, 6): each apex 0.64 times the one before, as the library's collider."""
    _check_apexes(student, feedback, "backtrack", 0.8, 0.01, 6, "bounce_heights('backtrack', eps=0.8, h=0.01, "
                  "bounces=6)", False)


@pytest.mark.points(1)
def test_bounce_heights_project(student, feedback):
    """bounce_heights('project', 1, 10 ms, 4): the ball climbs, as with the library's collider."""
    _check_apexes(student, feedback, "project", 1.0, 0.01, 4, "bounce_heights('project', eps=1, h=0.01, bounces=4)",
                  False)


@pytest.mark.points(2)
@pytest.mark.hidden
def test_bounce_heights_random(student, rng, feedback):
    """bounce_heights matches the library's collider at random restitutions and steps, both fixes."""
    for method in ("backtrack", "project"):
        while True:  # a step grid on which no landing falls within rounding of the floor
            eps, h, bounces = float(rng.uniform(0.7, 1.0)), float(rng.uniform(0.003, 0.02)), int(rng.integers(3, 7))
            if not _reference_apexes(method, eps, h, bounces)[1]:
                break
        _check_apexes(student, feedback, method, eps, h, bounces, f"bounce_heights({method!r}) at a random "
                      "restitution and step", True)


# -- incline_run ---------------------------------------------------------------------------------


@memoized
def _reference_incline(theta, mu, eps, h, T, variant=None):
    """The notebook's incline loop with the library's response: (s, v_t, v_n)."""
    n, t = np.array([np.sin(theta), np.cos(theta)]), np.array([np.cos(theta), -np.sin(theta)])
    x, v = np.zeros(2), np.zeros(2)
    v_rest = 0.0 if variant == "no resting contact" else 2 * G * h
    for _ in range(round(T / h)):  # a loop over time steps
        v = v + h * np.array([0.0, -G])
        if variant == "respond after moving":
            x = x + h * v
            if n @ x < 0:
                x = x - (n @ x) * n
                v = _response(v[None], n[None], eps, mu, v_rest)[0]
            continue
        if n @ x <= 1e-12:
            v = _response(v[None], n[None], eps, mu, v_rest)[0]
        x = x + h * v
        x = x - min(n @ x, 0.0) * n
    return np.array([t @ x, t @ v, n @ v])


def _check_incline(student, theta, mu, eps, h, T, call, hidden):
    got = student.call("incline_run", theta, mu, eps, h, T)
    if not isinstance(got, tuple) or len(got) != 3:
        raise GradingFailure(f"{call} returned {type(got).__name__}, expected (s, v_t, v_n)")
    value = _numbers(got, f"(s, v_t, v_n) of {call}")
    below = np.tan(theta) < mu
    if below and np.all(np.isfinite(value)) and np.any(value != 0):
        if abs(value[2]) > 1e-9:
            raise GradingFailure(f"{call}: below the friction angle the particle must rest, but it moves and its "
                                 "normal velocity is not zero: it chatters; a contact approaching no faster than "
                                 "v_rest = 2 g h is resting and gets no restitution")
        creep = _reference_incline(theta, mu, eps, h, T, "respond after moving")
        if np.allclose(value, creep, rtol=1e-6, atol=1e-12):
            raise GradingFailure(f"{call}: below the friction angle the particle must rest, but it creeps down the "
                                 "slope: respond to the velocity before moving the particle, or it moves by the "
                                 "velocity that friction then removes")
    n_steps = round(T / h)
    a = G * (np.sin(theta) - mu * np.cos(theta))
    law = np.array([a * h * h * n_steps * (n_steps + 1) / 2, a * n_steps * h, 0.0]) if not below else np.zeros(3)
    mirrored = "your particle slides up the slope, towards -t: the incline is built the wrong way round (a " \
               "rotation transposed?); it goes down towards +x, n = (sin theta, cos theta), t = (cos theta, -sin theta)"
    expect_array(value, _reference_incline(theta, mu, eps, h, T), f"(s, v_t, v_n) of {call}", rtol=1e-9, atol=1e-12,
                 show_values=not hidden, hints={mirrored: law * [-1.0, -1.0, 1.0]} if not below else None)
    expect_array(value, law, f"(s, v_t, v_n) of {call} against Coulomb's law", rtol=1e-9, atol=1e-12,
                 show_values=not hidden)


@pytest.mark.points(2)
def test_incline_rests_below_the_friction_angle(student):
    """incline_run at 20 degrees, mu = 0.5 (friction angle 26.6 degrees), eps = 0.5: the particle does not move."""
    _check_incline(student, np.radians(20.0), 0.5, 0.5, 0.01, 1.0, "incline_run(theta=20 degrees, mu=0.5, eps=0.5, "
                   "h=0.01, T=1)", False)


@pytest.mark.points(1)
def test_incline_slides_above_the_friction_angle(student):
    """incline_run at 35 degrees, mu = 0.5: the particle slides with a = g (sin - mu cos), exactly for the steps taken."""
    _check_incline(student, np.radians(35.0), 0.5, 0.5, 0.01, 1.0, "incline_run(theta=35 degrees, mu=0.5, eps=0.5, "
                   "h=0.01, T=1)", False)


@pytest.mark.points(2)
@pytest.mark.hidden
def test_incline_random(student, rng):
    """incline_run rests below and slides above random friction angles, at random restitutions, steps and durations."""
    for factor in (rng.uniform(0.4, 0.9), rng.uniform(1.1, 1.6)):
        mu = float(rng.uniform(0.2, 0.8))
        theta = float(min(factor * np.arctan(mu), np.radians(80.0)))
        _check_incline(student, theta, mu, float(rng.uniform(0.0, 0.9)), float(rng.uniform(0.002, 0.02)),
                       float(rng.uniform(0.5, 1.5)), "incline_run on a random incline "
                       f"{'below' if factor < 1 else 'above'} its friction angle", True)
