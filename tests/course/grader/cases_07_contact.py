"""Wrong and alternative submissions of exercise 07_contact (format: see exercise_corpus.py)."""

EXERCISE = "07_contact"

RESPONSE = ["test_contact_response_by_hand", "test_contact_response_random"]
COLLIDE = ["test_collide_ball", "test_collide_random_surfaces"]
STEP = ["test_bounce_step_by_hand[project]", "test_bounce_step_by_hand[backtrack]", "test_bounce_step_random"]
HEIGHTS = ["test_bounce_heights_backtrack", "test_bounce_heights_project", "test_bounce_heights_random"]
INCLINE = ["test_incline_rests_below_the_friction_angle", "test_incline_slides_above_the_friction_angle",
           "test_incline_random"]


def _response(normal="-ec * vn[:, None] * n", impulse="(1.0 + e) * np.abs(vn)", removed="np.minimum(mu * dv, speed)",
              approaching="vn < 0", e="np.where(approach & (-vn <= v_rest), 0.0, eps)"):
    """contact_response written plainly, with its pieces replaceable (typical mistakes)."""
    return f'''
def contact_response(v, n, eps, mu, v_rest=0.0):
    v, n = np.asarray(v, dtype=float), np.asarray(n, dtype=float)
    vn = np.sum(v * n, axis=1)
    approach = {approaching}
    e = {e}
    ec = e[:, None]
    v_t = v - vn[:, None] * n
    dv = {impulse}
    speed = np.linalg.norm(v_t, axis=1)
    removed = {removed}
    t_hat = np.divide(v_t, speed[:, None], out=np.zeros_like(v_t), where=speed[:, None] > 0)
    new = v_t - removed[:, None] * t_hat + {normal}
    return np.where(approach[:, None], new, v)
'''


def _incline(body):
    return f'''
def incline_run(theta, mu, eps, h, T):
{body}
'''


_INCLINE_LOOP = '''    x, v = np.zeros(2), np.zeros(2)
    for _ in range(round(T / h)):
        v = v + h * np.array([0.0, -g])
        if n @ x <= 1e-12:
            v = contact_response(v[None], n[None], eps, mu, 2 * g * h)[0]
        x = x + h * v - min(n @ (x + h * v), 0.0) * n
    return float(t @ x), float(t @ v), float(n @ v)'''

_SLOPE = '''    n, t = np.array([np.sin(theta), np.cos(theta)]), np.array([np.cos(theta), -np.sin(theta)])
'''


REJECTED = {
    # A sign: the normal part keeps its direction, the particle goes on into the solid.
    "normal_part_not_reversed": {
        "culprit": "contact_response",
        "replace": {"contact_response": _response(normal="ec * vn[:, None] * n")},
        "fails": {RESPONSE[0]: "your result matches v_t + eps v_n: the normal part is not reversed",
                  RESPONSE[1]: "the normal part is not reversed"},
    },
    # Restitution on the whole velocity, the tangential part scaled by eps too.
    "restitution_on_the_whole_velocity": {
        "culprit": "contact_response",
        "replace": {"contact_response": _response(normal="-ec * vn[:, None] * n + (ec - 1) * (v_t - removed[:, None] * t_hat)")},
        "fails": {RESPONSE[0]: "your result matches restitution on the whole velocity: only the normal part is "
                               "scaled by eps"},
        "passes": COLLIDE[:1],
    },
    # Restitution applied twice: the normal part reflected with eps, then scaled by eps once more.
    "restitution_applied_twice": {
        "culprit": "contact_response",
        "replace": {"contact_response": _response(normal="-ec * ec * vn[:, None] * n")},
        "fails": {RESPONSE[0]: "your result matches restitution applied twice (-eps^2 v_n)",
                  "test_bounce_heights_backtrack": "`bounce_heights` calls `contact_response` (through `bounce_step`), "
                                                   "which fails its own tests"},
        "passes": COLLIDE[:1],
    },
    # Friction that removes mu (1 + eps) |v . n| of tangential speed whatever the particle had: it reverses slow ones.
    "friction_reverses_the_motion": {
        "culprit": "contact_response",
        "replace": {"contact_response": _response(removed="mu * dv")},
        "fails": {RESPONSE[0]: "your result matches friction that reverses the tangential velocity",
                  INCLINE[0]: "`incline_run` calls `contact_response`, which fails its own tests"},
        "passes": COLLIDE[:1] + HEIGHTS[:2],
    },
    # The tangential impulse bounded by mu |v . n|, without the 1 + eps of the normal impulse.
    "friction_without_the_restitution_part": {
        "culprit": "contact_response",
        "replace": {"contact_response": _response(removed="np.minimum(mu * np.abs(vn), speed)")},
        "fails": {RESPONSE[0]: "your result matches friction bounded by mu |v . n|: the tangential impulse is at most "
                               "mu times the normal one"},
        "passes": COLLIDE[:1] + INCLINE[:2],
    },
    # Every contact responded, also particles that already move away from the surface.
    "separating_particles_responded": {
        "culprit": "contact_response",
        "replace": {"contact_response": _response(approaching="np.ones(len(vn), dtype=bool)",
                                                  e="np.where(np.abs(vn) <= v_rest, 0.0, eps)")},
        "fails": {RESPONSE[0]: "your result matches separating particles responded too: a particle with v . n >= 0 "
                               "already moves away",
                  RESPONSE[1]: "separating particles responded too"},
    },
    # No resting contact: every approaching contact bounces with eps, however slow.
    "resting_contacts_bounce": {
        "culprit": "contact_response",
        "replace": {"contact_response": _response(e="np.full(len(vn), float(eps))")},
        "fails": {RESPONSE[0]: "your result matches resting contacts that bounce: a contact with |v . n| <= v_rest "
                               "gets no restitution",
                  INCLINE[0]: "it chatters; a contact approaching no faster than v_rest = 2 g h is resting"},
        "passes": COLLIDE[:1] + STEP + HEIGHTS[:2],
    },
    # The projection with the wrong sign: the particles go deeper into the solid.
    "projection_along_plus_H_n": {
        "culprit": "collide",
        "replace": {"collide": '''
def collide(x, v, H, n, eps, mu, v_rest=0.0):
    x, v = np.array(x, dtype=float), np.array(v, dtype=float)
    inside = np.asarray(H) < 0
    x[inside] = x[inside] + np.asarray(H)[inside, None] * np.asarray(n)[inside]
    v[inside] = contact_response(v[inside], np.asarray(n)[inside], eps, mu, v_rest)
    return x, v
'''},
        "fails": {COLLIDE[0]: "your result matches x + H n: the particles moved further into the solid",
                  COLLIDE[1]: "the closest surface point is x - H n"},
        "passes": RESPONSE + STEP + HEIGHTS + INCLINE,
    },
    # Every particle put on the surface, those outside too: they stick to it.
    "every_particle_projected": {
        "culprit": "collide",
        "replace": {"collide": '''
def collide(x, v, H, n, eps, mu, v_rest=0.0):
    x = np.asarray(x, dtype=float) - np.asarray(H)[:, None] * np.asarray(n)
    return x, contact_response(v, n, eps, mu, v_rest)
'''},
        "fails": {COLLIDE[0]: "your result matches every particle projected onto the surface, those outside too: "
                              "only H < 0 is a collision"},
        "passes": RESPONSE + STEP + HEIGHTS + INCLINE,
    },
    # The wrong time of evaluation: backtracking finds the contact time, but responds to the start's velocity.
    "backtrack_with_the_velocity_of_the_start": {
        "culprit": "bounce_step",
        "replace": {"bounce_step": '''
def bounce_step(y, v, h, eps, method):
    y1, v1 = y + h * v - g * h * h / 2, v - g * h
    if y1 >= 0:
        return y1, v1, False
    tau = h if method == "project" else (v + np.sqrt(v * v + 2 * g * y)) / g
    v_hit = v1 if method == "project" else v
    v_up = contact_response(np.array([[0.0, v_hit]]), up, eps, 0.0)[0, 1]
    r = h - tau
    return v_up * r - g * r * r / 2, v_up - g * r, True
'''},
        "fails": {STEP[1]: "your result matches a response to the velocity of the start of the step: respond to "
                           "the velocity at the moment of contact",
                  "test_bounce_heights_backtrack": "off by"},
        "passes": RESPONSE + COLLIDE + [STEP[0], "test_bounce_heights_project"] + INCLINE,
        "diagnosis": {STEP[1]: "respond to the velocity at the moment of contact, v0 - g tau"},
    },
    # Backtracking that stops at the contact: the ball left on the floor with its new velocity.
    "backtrack_left_on_the_floor": {
        "culprit": "bounce_step",
        "replace": {"bounce_step": '''
def bounce_step(y, v, h, eps, method):
    y1, v1 = y + h * v - g * h * h / 2, v - g * h
    if y1 >= 0:
        return y1, v1, False
    tau = h if method == "project" else (v + np.sqrt(v * v + 2 * g * y)) / g
    v_up = contact_response(np.array([[0.0, v - g * tau]]), up, eps, 0.0)[0, 1]
    return 0.0, v_up, True
'''},
        "fails": {STEP[1]: "your result matches the ball left on the floor with the new velocity: fly the rest of "
                           "the step from the floor"},
        "passes": RESPONSE + COLLIDE + [STEP[0], "test_bounce_heights_project"] + INCLINE,
    },
    # The height at the end of the step taken for the apex.
    "apex_without_the_flight": {
        "culprit": "bounce_heights",
        "replace": {"bounce_heights": '''
def bounce_heights(method, eps, h, bounces):
    y, v = 1.0, -0.25
    apex = [y + v * v / (2 * g)]
    while len(apex) <= bounces:
        y, v, touched = bounce_step(y, v, h, eps, method)
        if touched:
            apex.append(y)
    return np.array(apex)
'''},
        "fails": {"test_bounce_heights_backtrack": "your result matches y alone: the apex is y + v^2 / (2 g)"},
        "passes": RESPONSE + COLLIDE + STEP + INCLINE,
    },
    # The incline's contact answered after the move, as for a bounce: the particle creeps down below the friction angle.
    "incline_response_after_the_move": {
        "culprit": "incline_run",
        "replace": {"incline_run": _incline(_SLOPE + '''    x, v = np.zeros(2), np.zeros(2)
    for _ in range(round(T / h)):
        v = v + h * np.array([0.0, -g])
        x = x + h * v
        if n @ x < 0:
            x = x - (n @ x) * n
            v = contact_response(v[None], n[None], eps, mu, 2 * g * h)[0]
    return float(t @ x), float(t @ v), float(n @ v)''')},
        "fails": {INCLINE[0]: "it creeps down the slope: respond to the velocity before moving the particle"},
        "passes": RESPONSE + COLLIDE + STEP + HEIGHTS,
    },
    # A transpose: the incline's frame rotated the wrong way (R where R^T was meant): it goes down towards -x, and t
    # points up the slope.
    "incline_rotated_the_wrong_way": {
        "culprit": "incline_run",
        "replace": {"incline_run": _incline('''    R = np.array([[np.cos(theta), -np.sin(theta)], [np.sin(theta), np.cos(theta)]])
    n, t = R @ np.array([0.0, 1.0]), R @ np.array([1.0, 0.0])
''' + _INCLINE_LOOP)},
        "fails": {INCLINE[1]: "your particle slides up the slope, towards -t: the incline is "
                              "built the wrong way round"},
        "passes": RESPONSE + COLLIDE + STEP + HEIGHTS + [INCLINE[0]],
    },
    # The library's response: a rule of the exercise.
    "library_response": {
        "culprit": "contact_response",
        "replace": {"contact_response": '''
from particles.collisions import respond

def contact_response(v, n, eps, mu, v_rest=0.0):
    return respond(v, n, eps, mu)[0]
'''},
        "fails": {RESPONSE[0]: "which this exercise forbids: it is the response you are asked to write"},
    },
}


CORRECT = {
    # The response by masks and a clip, the projection with np.where, the contact time from the start of the step,
    # the apexes with a for loop, the incline through a rotation matrix and its own resting test.
    "written_differently": {
        "replace": {
            "contact_response": '''
def contact_response(v, n, eps, mu, v_rest=0.0):
    v, n = np.array(v, dtype=float), np.asarray(n, dtype=float)
    vn = np.einsum("kd,kd->k", v, n)
    hit = vn < 0
    e = np.where(np.abs(vn) > v_rest, eps, 0.0)
    tangential = v - vn[:, None] * n
    length = np.sqrt(np.einsum("kd,kd->k", tangential, tangential))
    keep = np.clip(1.0 - mu * (1.0 + e) * np.abs(vn) / np.maximum(length, 1e-300), 0.0, 1.0)
    v[hit] = keep[hit, None] * tangential[hit] - e[hit, None] * vn[hit, None] * n[hit]
    return v
''',
            "collide": '''
def collide(x, v, H, n, eps, mu, v_rest=0.0):
    H, n = np.asarray(H, dtype=float), np.asarray(n, dtype=float)
    inside = (H < 0)[:, None]
    x_new = np.where(inside, np.asarray(x, dtype=float) - H[:, None] * n, x)
    v_new = np.where(inside, contact_response(v, n, eps, mu, v_rest), v)
    return x_new, v_new
''',
            "bounce_step": '''
def bounce_step(y, v, h, eps, method):
    y_end, v_end = y + h * v - 0.5 * g * h**2, v - g * h
    if not y_end < 0:
        return y_end, v_end, False
    tau = h if method == "project" else (v + (v**2 + 2 * g * y) ** 0.5) / g
    hit = v_end if method == "project" else v - g * tau
    new = contact_response(np.array([[0.0, hit]]), up, eps, 0.0)[0, 1]
    rest = h - tau
    return new * rest - 0.5 * g * rest**2, new - g * rest, True
''',
            "bounce_heights": '''
def bounce_heights(method, eps, h, bounces):
    state, tops = (1.0, -0.25), [1.0 + 0.25**2 / (2 * g)]
    for _ in range(10**6):
        if len(tops) > bounces:
            break
        y, v, hit = bounce_step(*state, h, eps, method)
        state = (y, v)
        if hit:
            tops.append(y + v**2 / (2 * g))
    return np.asarray(tops)
''',
            "incline_run": '''
def incline_run(theta, mu, eps, h, T):
    R = np.array([[np.cos(theta), np.sin(theta)], [-np.sin(theta), np.cos(theta)]])
    t, n = R[:, 0], R[:, 1]
    x, v = np.zeros(2), np.zeros(2)
    for _ in range(int(round(T / h))):
        v = v - [0.0, g * h]
        touching = np.dot(n, x) <= 1e-12
        v = contact_response(v.reshape(1, 2), n.reshape(1, 2), eps, mu, 2 * g * h)[0] if touching else v
        x = x + h * v
        x = x - min(np.dot(n, x), 0.0) * n
    return float(np.dot(t, x)), float(np.dot(t, v)), float(np.dot(n, v))
''',
        },
    },
}
