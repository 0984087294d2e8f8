"""Wrong and alternative submissions of exercise 04_discretization (format: ``exercise_corpus.py``)."""

EXERCISE = "04_discretization"

_STIFFNESS_HEAD = '''
def spring_stiffness(nx, ny, width, height, Y):
    """Stiffness of each spring, by kind."""
    dx, dy = width / (nx - 1), height / (ny - 1)
    pairs = cloth_springs(nx, ny)
'''

_MASSES_TESTS = ["test_masses_small_grid", "test_masses_random"]
_STIFFNESS_TESTS = ["test_structural_small_grid", "test_shear_small_grid", "test_flexion_small_grid",
                    "test_stiffness_random"]
_EXPONENT_TESTS = ["test_fit_exponent_power_law", "test_fit_exponent_random", "test_fit_exponent_library_steps"]

REJECTED = {
    # the mass of the whole sheet on every particle: the density times the total area, never divided
    "mass_of_the_whole_sheet": {
        "culprit": "particle_masses",
        "replace": {"particle_masses": '''
def particle_masses(nx, ny, width, height, rho):
    """Mass of each particle."""
    return np.full(nx * ny, rho * width * height)
'''},
        "fails": {"test_masses_small_grid": "the mass of the whole sheet, rho W H, on every particle",
                  "test_masses_random": "add up to",
                  "test_sag_converges": "expected the sag of that fabric",
                  "test_sag_converges_random_fabric": "within 3% at every resolution",
                  "test_stable_step": "stable_step(nx=8"},
        "passes": _STIFFNESS_TESTS + _EXPONENT_TESTS,
    },
    # a whole cell on every particle: edges and corners are too heavy, the total converges only as 1/n
    "mass_ignores_boundary_cells": {
        "culprit": "particle_masses",
        "replace": {"particle_masses": '''
def particle_masses(nx, ny, width, height, rho):
    """Mass of each particle: density times the area of a cell."""
    dx, dy = width / (nx - 1), height / (ny - 1)
    return rho * dx * dy * np.ones(nx * ny)
'''},
        "fails": {"test_masses_small_grid": "rho dx dy on every particle (edge particles stand for half a cell",
                  "test_masses_random": "add up to",
                  "test_sag_converges": "off by +",
                  "test_sag_converges_random_fabric": "expected the sag of that fabric"},
        "passes": _STIFFNESS_TESTS + _EXPONENT_TESTS,
    },
    # stiffness proportional to the rest length instead of inversely (k = Y L0)
    "stiffness_grows_with_rest_length": {
        "culprit": "spring_stiffness",
        "replace": {"spring_stiffness": _STIFFNESS_HEAD + '''
    out = {}
    for kind, ij in pairs.items():
        L0 = np.hypot((ij[:, 1] % nx - ij[:, 0] % nx) * dx, (ij[:, 1] // nx - ij[:, 0] // nx) * dy)
        out[kind] = Y[kind] * L0
    return out
'''},
        "fails": {"test_structural_small_grid": "k proportional to the rest length",
                  "test_shear_small_grid": "k proportional to the rest length",
                  "test_flexion_small_grid": "k proportional to the rest length",
                  "test_stiffness_random": "is off by",
                  "test_sag_converges": "cloth_sag gives",
                  "test_sag_converges_random_fabric": "cloth_sag gives"},
        "passes": _MASSES_TESTS + _EXPONENT_TESTS,
    },
    # the naive constants of section 3 kept: the same mass and stiffnesses at every resolution (at 8 x 8 a stable
    # step 2% above the physical cloth's, which a check within 2% on either side let pass)
    "naive_constants": {
        "culprit": ["particle_masses", "spring_stiffness"],
        "replace": {
            "particle_masses": '''
def particle_masses(nx, ny, width, height, rho):
    """Mass of each particle: the tuned value."""
    return np.full(nx * ny, m_naive)
''',
            "spring_stiffness": _STIFFNESS_HEAD + '''
    return {kind: np.full(len(ij), k_naive[kind]) for kind, ij in pairs.items()}
'''},
        "fails": {"test_masses_small_grid": "but the sheet weighs rho W H = 3 kg; your particles all have the same "
                                            "mass: a corner stands for a quarter of a cell",
                  "test_structural_small_grid": "is off by",
                  "test_stiffness_random": "is off by",
                  "test_sag_converges": "off by +",
                  "test_sag_converges_random_fabric": "cloth_sag gives",
                  "test_stable_step": "stable_step(nx=8, ny=8, width=1, height=1, rho=0.2, Y={structural: 100, "
                                      "shear: 25, flexion: 10}) returned 6.32 ms, 2% above 2 / omega_max",
                  "test_stable_step_shrinks_like_the_spacing": "stable_step"},
        "passes": _EXPONENT_TESTS,
    },
    # log(spacing) fitted against log(h_max): the slope is 1 / p on exact power laws
    "exponent_on_swapped_axes": {
        "culprit": "fit_exponent",
        "replace": {"fit_exponent": '''
def fit_exponent(spacing, h_max):
    """Exponent of h_max ~ spacing^p."""
    return float(np.polyfit(np.log(h_max), np.log(spacing), 1)[0])
'''},
        "fails": {"test_fit_exponent_power_law": "returned p = 0.6667, expected 1.5; your result is the slope of "
                                                 "log(spacing) against log(h_max), the axes swapped",
                  "test_fit_exponent_random": "the axes swapped",
                  "test_fit_exponent_library_steps": "the axes swapped"},
        "passes": _MASSES_TESTS + _STIFFNESS_TESTS + ["test_sag_converges", "test_sag_converges_random_fabric",
                                                      "test_stable_step", "test_stable_step_shrinks_like_the_spacing"],
    },
    # the stable step from the rough estimate omega_max ~ sqrt(k / m) of the stiffest spring and the lightest
    # particle: 1.3% to 6% above 2 / omega_max, an unstable step (within 2% of it on fabrics with little shear)
    "stable_step_from_the_stiffest_spring": {
        "culprit": "stable_step",
        "replace": {"stable_step": '''
def stable_step(nx, ny, width, height, rho, Y):
    """2 / omega_max, with omega_max = sqrt(k / m) of the stiffest spring and the lightest particle."""
    m = particle_masses(nx, ny, width, height, rho)
    k = spring_stiffness(nx, ny, width, height, Y)
    k_max = max(float(np.max(values)) for values in k.values())
    return 2.0 / np.sqrt(k_max / float(np.min(m)))
'''},
        "fails": {"test_stable_step": "3.1% above 2 / omega_max",
                  "test_stable_step_shrinks_like_the_spacing": "a step at which symplectic Euler blows up on it"},
        "passes": _MASSES_TESTS + _STIFFNESS_TESTS + _EXPONENT_TESTS + ["test_sag_converges",
                                                                        "test_sag_converges_random_fabric"],
    },
    # a flexion spring given the rest length of one cell (L0 = dx instead of 2 dx): four times too stiff
    "flexion_rest_length_of_one_cell": {
        "culprit": "spring_stiffness",
        "replace": {"spring_stiffness": _STIFFNESS_HEAD + '''
    wx, wy = np.ones(nx), np.ones(ny)
    wx[[0, -1]] = wy[[0, -1]] = 0.5

    def family(Yk, g, L):
        rows = Yk * width * wy[:, None] * dy / (nx - g) / (L * dx) ** 2 * np.ones((ny, nx - g))
        cols = Yk * height * wx[None, :] * dx / (ny - g) / (L * dy) ** 2 * np.ones((ny - g, nx))
        return np.concatenate([rows.ravel(), cols.ravel()])

    return {"structural": family(Y["structural"], 1, 1),
            "shear": np.full(len(pairs["shear"]), Y["shear"] * dx * dy / 2 / (dx**2 + dy**2)),
            "flexion": family(Y["flexion"], 2, 1)}
'''},
        "fails": {"test_flexion_small_grid": "L0 = dx for a flexion spring",
                  "test_stiffness_random": "the 'flexion' stiffnesses"},
        "passes": _MASSES_TESTS + ["test_structural_small_grid", "test_shear_small_grid"] + _EXPONENT_TESTS,
    },
    # ln of the spacing against log10 of the steps: the slope is p / ln(10)
    "exponent_with_mixed_logarithms": {
        "culprit": "fit_exponent",
        "replace": {"fit_exponent": '''
def fit_exponent(spacing, h_max):
    """Exponent of h_max ~ spacing^p."""
    return float(np.polyfit(np.log(spacing), np.log10(h_max), 1)[0])
'''},
        "fails": {"test_fit_exponent_power_law": "returned p = 0.6514, expected 1.5; your result is the slope divided by "
                                                 "ln(10) = 2.303: log10 of h_max against ln of the spacing",
                  "test_fit_exponent_random": "your result is the slope divided by ln(10) = 2.303",
                  "test_fit_exponent_library_steps": "use the same logarithm on both axes"},
        "passes": _MASSES_TESTS + _STIFFNESS_TESTS + ["test_sag_converges", "test_stable_step"],
    },
    # the mean drop of all particles instead of the drop of the lowest one: it converges too, to a third of the sag
    "mean_sag_instead_of_the_lowest_point": {
        "culprit": "sag",
        "replace": {"sag": '''
def sag(system):
    """Static sag: how far the cloth comes down, on average, from the flat sheet to equilibrium."""
    z_flat = system.X[:, 0, 2].copy()
    relax(system, h=0.2)
    return float(np.mean(z_flat - system.X[:, 0, 2]))
'''},
        "fails": {"test_sag_converges": "your sag is the mean drop of the particles, not the drop of the lowest "
                                        "particle: the sag is z_flat.min() - z.min()",
                  "test_sag_converges_random_fabric": "your sag is the mean drop of the particles"},
        "passes": _MASSES_TESTS + _STIFFNESS_TESTS + _EXPONENT_TESTS + ["test_stable_step"],
    },
    # the library's rule instead of a derivation: caught in the code (an import) and at run time (a computed name)
    "library_rule": {
        "culprit": ["particle_masses", "spring_stiffness", "cloth_sag"],
        "replace": {
            "particle_masses": '''
from particles.massspring import cloth_masses


def particle_masses(nx, ny, width, height, rho):
    """The library's masses."""
    return cloth_masses(nx, ny, width, height, rho)
''',
            "spring_stiffness": '''
import importlib


def spring_stiffness(nx, ny, width, height, Y):
    """The library's stiffnesses, under a computed name."""
    rule = getattr(importlib.import_module("particles.massspring"), "cloth_" + "stiffness")
    return rule(nx, ny, width, height, Y)
''',
            "cloth_sag": '''
from particles.massspring import cloth


def cloth_sag(nx, ny, width, height, rho, Y):
    """The library's physically scaled cloth, relaxed."""
    c = cloth(nx, ny, width, height, pins="top edge", scaling="physical", areal_density=rho,
              stretch_modulus=Y["structural"], shear_modulus=Y["shear"], flexion_modulus=Y["flexion"])
    return sag(c)
'''},
        "fails": {"test_masses_small_grid": "uses `particles.massspring.cloth_masses`, which this exercise forbids",
                  "test_structural_small_grid": "used a forbidden library function",
                  "test_sag_converges": "uses `particles.massspring.cloth`, which this exercise forbids",
                  "test_stable_step": "which this exercise forbids"},
        "passes": _EXPONENT_TESTS,
    },
}

REJECTED.update({
    # Every particle weighted 1: the boundary particles get the mass of a whole cell.
    "dual_weights_all_ones": {
        "culprit": "dual_weights",
        "replace": {"dual_weights": '''
def dual_weights(n):
    return np.ones(n)
'''},
        "fails": {"test_masses_small_grid": "your result matches rho dx dy on every particle (edge particles stand "
                                            "for half a cell, corners for a quarter) (`particle_masses` relies on "
                                            "`dual_weights`"},
    },
})


CORRECT = {
    # masses gathered cell by cell (a quarter of each cell to each of its corners), stiffnesses spring by
    # spring from the index pairs, the exponent by the closed-form least-squares slope
    "cell_by_cell_and_spring_by_spring": {
        "replace": {
            "particle_masses": '''
def particle_masses(nx, ny, width, height, rho):
    """Each cell's mass rho dx dy, a quarter to each of its four corners."""
    dx, dy = width / (nx - 1), height / (ny - 1)
    m = np.zeros((ny, nx))
    for di in (0, 1):
        for dj in (0, 1):
            m[dj:ny - 1 + dj, di:nx - 1 + di] += rho * dx * dy / 4
    return m.ravel()
''',
            "spring_stiffness": '''
def spring_stiffness(nx, ny, width, height, Y):
    """k = Y A / L0^2, one spring at a time."""
    dx, dy = width / (nx - 1), height / (ny - 1)

    def w(i, n):
        return 0.5 if i in (0, n - 1) else 1.0

    out = {}
    for kind, pairs in cloth_springs(nx, ny).items():
        k = np.empty(len(pairs))
        for s, (a, b) in enumerate(pairs):
            (ja, ia), (jb, ib) = divmod(int(a), nx), divmod(int(b), nx)
            if kind == "shear":
                k[s] = Y[kind] * (dx * dy / 2) / (dx**2 + dy**2)
            elif ja == jb:  # along row ja, spanning g cells
                g = ib - ia
                k[s] = Y[kind] * (width * w(ja, ny) * dy / (nx - g)) / (g * dx) ** 2
            else:  # along column ia
                g = jb - ja
                k[s] = Y[kind] * (height * w(ia, nx) * dx / (ny - g)) / (g * dy) ** 2
        out[kind] = k
    return out
''',
            "fit_exponent": '''
def fit_exponent(spacing, h_max):
    """Least-squares slope of log(h_max) against log(spacing), in closed form."""
    x, y = np.log(np.asarray(spacing, dtype=float)), np.log(np.asarray(h_max, dtype=float))
    x0, y0 = x - x.mean(), y - y.mean()
    return float(x0 @ y0 / (x0 @ x0))
''',
            "sag": '''
def sag(system):
    """Drop of the lowest particle, from the flat sheet to equilibrium."""
    before = np.min(system.X[:, 0, -1])
    relax(system, h=0.2)
    after = np.min(system.X[:, 0, -1])
    return before - after
'''},
    },
}
