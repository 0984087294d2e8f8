"""Wrong and alternative submissions of exercise 06_implicit_step (format: see exercise_corpus.py)."""

EXERCISE = "06_implicit_step"

JACOBIAN = ["test_spring_jacobian_at_an_angle", "test_spring_jacobian_compressed", "test_spring_jacobian_random"]
STIFFNESS = ["test_stiffness_matrix_three_particles", "test_stiffness_matrix_random"]
STEP = ["test_implicit_step_one_spring", "test_implicit_step_random"]
STRAIN = ["test_largest_strain_at_a_hundred_times_the_limit", "test_largest_strain_random"]
DAMPING = ["test_damping_rates_public", "test_damping_rates_random"]


def _jacobian(across):
    """spring_jacobian written as the master, with `across` as the factor of the transverse term."""
    return f'''
def spring_jacobian(xi, xj, k, L0):
    d = np.asarray(xi, dtype=float) - np.asarray(xj, dtype=float)
    L = np.linalg.norm(d)
    u = d / L
    uu = np.outer(u, u)
    return -k * (uu + ({across}) * (np.eye(2) - uu))
'''


def _stiffness(body):
    return f'''
def stiffness_matrix(x, ij, k, L0):
    x = np.asarray(x, dtype=float)
    n = len(x)
    K = np.zeros((2 * n, 2 * n))
    for (i, j), rest in zip(np.asarray(ij), np.asarray(L0, dtype=float)):
        J = spring_jacobian(x[i], x[j], k, rest)
{body}
    return K
'''


def _step(system, positions="x + h * v_new", dofs="np.repeat(np.asarray(free, dtype=bool), 2)"):
    return f'''
def implicit_step(x, v, h, m, ij, k, L0, g, free):
    x, v = np.asarray(x, dtype=float), np.asarray(v, dtype=float)
    n = len(x)
    F = spring_forces(x, ij, k, L0)
    F[:, -1] -= np.asarray(m) * g
    K = stiffness_matrix(x, ij, k, L0)
{system}
    dofs = {dofs}
    dv = np.zeros(2 * n)
    dv[dofs] = np.linalg.solve(A[np.ix_(dofs, dofs)], b[dofs])
    v_new = v + dv.reshape(n, 2)
    return {positions}, v_new
'''


def _rates(rest, divide):
    """damping_rates written as the master, with the energy at rest `rest` and the rate's divisor `divide`."""
    return f'''
def damping_rates(hs, T):
    rates = []
    for h in hs:
        x, v, N = x_taut + pluck, np.zeros_like(x_taut), round(T / h)
        E0 = taut_energy(x, v) - {rest}
        for _ in range(N):
            x, v = implicit_step(x, v, h, m_taut, ij_taut, k_taut, L0_taut, 0.0, free_taut)
        rates.append(-np.log((taut_energy(x, v) - {rest}) / E0) / ({divide}))
    return np.array(rates)
'''


_SYSTEM = '''    A = np.diag(np.repeat(m, 2)) - h**2 * K
    b = h * (F.ravel() + h * K @ v.ravel())'''

_BLOCKS = '''        a, b = slice(2 * i, 2 * i + 2), slice(2 * j, 2 * j + 2)
        K[a, a] += J
        K[b, b] += J
        K[a, b] -= J
        K[b, a] -= J'''


REJECTED = {
    # The force's derivative with the sign of the stiffness: +k [...] (the matrix -dF/dx of the lecture's K).
    "jacobian_sign_flipped": {
        "culprit": "spring_jacobian",
        "replace": {"spring_jacobian": '''
def spring_jacobian(xi, xj, k, L0):
    d = np.asarray(xi, dtype=float) - np.asarray(xj, dtype=float)
    L = np.linalg.norm(d)
    u = d / L
    uu = np.outer(u, u)
    return k * (uu + (1.0 - L0 / L) * (np.eye(2) - uu))
'''},
        "fails": {JACOBIAN[0]: "your result matches +k [u u^T + (1 - L0/L)(I - u u^T)]: the sign is wrong",
                  JACOBIAN[2]: "the sign is wrong"},
    },
    # Only the stiffness along the spring: the turning of u (the transverse term) is forgotten.
    "jacobian_transverse_term_missing": {
        "culprit": "spring_jacobian",
        "replace": {"spring_jacobian": '''
def spring_jacobian(xi, xj, k, L0):
    d = np.asarray(xi, dtype=float) - np.asarray(xj, dtype=float)
    u = d / np.linalg.norm(d)
    return -k * np.outer(u, u)
'''},
        "fails": {JACOBIAN[0]: "your result matches -k u u^T alone: the transverse term -k (1 - L0/L)(I - u u^T) is "
                               "missing",
                  JACOBIAN[1]: "the exact derivative keeps the transverse term -k (1 - L0/L)(I - u u^T)"},
    },
    # The stretch ratio upside down in the transverse term.
    "jacobian_stretch_ratio_upside_down": {
        "culprit": "spring_jacobian",
        "replace": {"spring_jacobian": _jacobian("1.0 - L / L0")},
        "fails": {JACOBIAN[0]: "your result matches -k [u u^T + (1 - L/L0)(I - u u^T)]: the factor across the "
                               "spring is 1 - L0/L, not 1 - L/L0",
                  JACOBIAN[2]: "the factor across the spring is 1 - L0/L"},
    },
    # Choi and Ko's clamp put into the Jacobian: right for stretched springs, not the derivative of a compressed one.
    "jacobian_clamped": {
        "culprit": "spring_jacobian",
        "replace": {"spring_jacobian": _jacobian("max(0.0, 1.0 - L0 / L)")},
        "fails": {JACOBIAN[1]: "your result matches -k u u^T, the clamped Jacobian of a compressed spring",
                  JACOBIAN[2]: "the exact derivative keeps the transverse term"},
        "passes": [JACOBIAN[0]],
    },
    # The off-diagonal blocks added with the diagonal's sign.
    "stiffness_off_diagonal_sign": {
        "culprit": "stiffness_matrix",
        "replace": {"stiffness_matrix": _stiffness(_BLOCKS.replace("K[a, b] -= J", "K[a, b] += J")
                                                   .replace("K[b, a] -= J", "K[b, a] += J"))},
        "fails": {STIFFNESS[0]: "your result matches blocks K_ij = +J: the off-diagonal blocks are -J",
                  STIFFNESS[1]: "the off-diagonal blocks are -J"},
        "passes": JACOBIAN,
    },
    # The matrix laid out axis by axis (all x, then all y): the transpose of the particles-by-axes layout.
    "stiffness_axis_major_layout": {
        "culprit": "stiffness_matrix",
        "replace": {"stiffness_matrix": _stiffness('''        for a in range(2):
            for b in range(2):
                K[a * n + i, b * n + i] += J[a, b]
                K[a * n + j, b * n + j] += J[a, b]
                K[a * n + i, b * n + j] -= J[a, b]
                K[a * n + j, b * n + i] -= J[a, b]''')},
        "fails": {STIFFNESS[0]: "your result matches the coordinates laid out axis by axis (entry a n + p)",
                  STIFFNESS[1]: "the layout is particle by particle, 2 p + a"},
        "passes": JACOBIAN,
    },
    # `=` instead of `+=` on the diagonal blocks: a particle shared by two springs keeps only the last one's.
    "stiffness_shared_particle_overwritten": {
        "culprit": "stiffness_matrix",
        "replace": {"stiffness_matrix": _stiffness(_BLOCKS.replace("K[a, a] += J", "K[a, a] = J")
                                                   .replace("K[b, b] += J", "K[b, b] = J"))},
        "fails": {STIFFNESS[0]: "your result matches a diagonal block overwritten where two springs share a particle"},
        "passes": JACOBIAN,
    },
    # The right-hand side of an explicit step: the force linearized about the start only, h K v forgotten.
    "step_without_h_K_v": {
        "culprit": "implicit_step",
        "replace": {"implicit_step": _step(_SYSTEM.replace("h * (F.ravel() + h * K @ v.ravel())", "h * F.ravel()"))},
        "fails": {STEP[0]: "your result matches a step without the h K v term: the force is linearized about the end "
                           "of the step",
                  STEP[1]: "a step without the h K v term"},
        "passes": JACOBIAN + STIFFNESS,
    },
    # One h too few in the matrix.
    "step_h_instead_of_h_squared": {
        "culprit": "implicit_step",
        "replace": {"implicit_step": _step(_SYSTEM.replace("- h**2 * K", "- h * K"))},
        "fails": {STEP[0]: "your result matches a step with M - h K instead of M - h^2 K",
                  STEP[1]: "M - h K instead of M - h^2 K"},
        "passes": JACOBIAN + STIFFNESS,
    },
    # The positions moved with the velocity of the start of the step: the wrong time of evaluation.
    "step_positions_from_the_old_velocity": {
        "culprit": "implicit_step",
        "replace": {"implicit_step": _step(_SYSTEM, positions="x + h * v")},
        "fails": {STEP[0]: "your result matches a step whose positions use the old velocity, x + h v, instead of the "
                           "new one"},
        "passes": JACOBIAN + STIFFNESS,
    },
    # The pinned particle solved for like the others: it falls.
    "step_pins_not_left_out": {
        "culprit": "implicit_step",
        "replace": {"implicit_step": _step(_SYSTEM, dofs="np.ones(2 * n, dtype=bool)")},
        "fails": {STEP[0]: "moved pinned particle 0; a pinned particle keeps its position and a zero velocity",
                  STEP[1]: "leave its rows and columns out of the system"},
        "passes": JACOBIAN + STIFFNESS,
    },
    # The measurement keeps the last step's strain, not the largest.
    "strain_of_the_last_step": {
        "culprit": "largest_strain",
        "replace": {"largest_strain": '''
def largest_strain(h, T, kick):
    x, v = x0.copy(), np.zeros_like(x0)
    v[:, 0] = kick * (x0[0, 1] - x0[:, 1])
    for _ in range(round(T / h)):
        x, v = implicit_step(x, v, h, m, ij, k, L0, g, free)
    L = np.linalg.norm(x[ij[:, 0]] - x[ij[:, 1]], axis=1)
    return float(np.max(L / L0 - 1.0))
'''},
        "fails": {STRAIN[0]: "your result matches the strain after the last step only: return the largest over all "
                             "the steps"},
        "passes": JACOBIAN + STIFFNESS + STEP + DAMPING,
    },
    # The decay rate of the energy read as if it were the amplitude's: no 1/2.
    "damping_rate_without_the_half": {
        "culprit": "damping_rates",
        "replace": {"damping_rates": _rates(rest="E_rest", divide="N * h")},
        "fails": {DAMPING[0]: "your result matches -ln(E_N / E_0) / (N h), without the 1/2",
                  DAMPING[1]: "without the 1/2"},
        "passes": JACOBIAN + STIFFNESS + STEP + STRAIN,
    },
    # The whole energy, the taut string's own included: its springs are stretched at rest, so the ratio hardly moves.
    "damping_rate_of_the_whole_energy": {
        "culprit": "damping_rates",
        "replace": {"damping_rates": _rates(rest="0.0", divide="2 * N * h")},
        "fails": {DAMPING[0]: "your result matches the rate of the whole energy, E_rest included: subtract the energy "
                              "of the taut string at rest"},
        "passes": JACOBIAN + STIFFNESS + STEP + STRAIN,
    },
    # The library's Jacobians instead of one's own: a rule of the exercise.
    "library_jacobians": {
        "culprit": "stiffness_matrix",
        "replace": {"stiffness_matrix": '''
from particles.forces import Springs

def stiffness_matrix(x, ij, k, L0):
    x = np.asarray(x, dtype=float)
    springs = Springs(np.asarray(ij), rest_length=np.asarray(L0, dtype=float), k=k)
    return springs.jacobians(x, np.zeros_like(x), clamp=False)[0].toarray()
'''},
        "fails": {STIFFNESS[0]: "used a forbidden library function at code cell",
                  STIFFNESS[1]: "is not allowed in this exercise: it is the Jacobian you are asked to write"},
        "passes": JACOBIAN,
    },
}


CORRECT = {
    # The Jacobian by components, the matrix by vectorized blocks and np.add.at, the pins kept in the system as
    # identity rows (Baraff and Witkin's filter), the energies through a helper, the rates in one expression.
    "components_and_a_filter": {
        "replace": {
            "spring_jacobian": '''
def spring_jacobian(xi, xj, k, L0):
    dx, dy = float(xi[0] - xj[0]), float(xi[1] - xj[1])
    L = (dx * dx + dy * dy) ** 0.5
    ux, uy = dx / L, dy / L
    c = 1.0 - L0 / L
    return -k * np.array([[ux * ux + c * (1 - ux * ux), ux * uy - c * ux * uy],
                          [ux * uy - c * ux * uy, uy * uy + c * (1 - uy * uy)]])
''',
            "stiffness_matrix": '''
def stiffness_matrix(x, ij, k, L0):
    x, ij = np.asarray(x, dtype=float), np.asarray(ij)
    d = x[ij[:, 0]] - x[ij[:, 1]]
    L = np.sqrt(np.einsum("sa,sa->s", d, d))
    u = d / L[:, None]
    uu = np.einsum("sa,sb->sab", u, u)
    J = -k * (uu + (1 - np.asarray(L0) / L)[:, None, None] * (np.eye(2) - uu))
    K4 = np.zeros((len(x), 2, len(x), 2))
    for p, q, sign in ((0, 0, 1), (1, 1, 1), (0, 1, -1), (1, 0, -1)):
        np.add.at(K4, (ij[:, p], slice(None), ij[:, q]), sign * J)
    return K4.reshape(2 * len(x), 2 * len(x))
''',
            "implicit_step": '''
def implicit_step(x, v, h, m, ij, k, L0, g, free):
    x, v = np.array(x, dtype=float), np.array(v, dtype=float)
    F = spring_forces(x, ij, k, L0) - np.outer(m, [0.0, g])
    K = stiffness_matrix(x, ij, k, L0)
    S = np.diag(np.repeat(np.asarray(free, dtype=float), 2))     # the filter: zero rows and columns of pins
    A = S @ (np.diag(np.repeat(m, 2)) - h * h * K) @ S + (np.eye(2 * len(x)) - S)
    dv = np.linalg.solve(A, S @ (h * F.ravel() + h * h * K @ v.ravel()))
    v_new = v + dv.reshape(v.shape)
    return x + h * v_new, v_new
''',
        },
    },
}
