"""The key numbers each lecture states are the numbers its cells print.

For every lecture a small table of claims: a regular expression over the
printed text of the executed notebook (stream output and ``text/plain``
results, all cells concatenated) whose first group is the number, the value
the lecture states, and a tolerance. Seeded or exact results get a tight
tolerance; timings only loose bounds, written ``(below, above)``: the value
must lie in ``[expected - below, expected + above]``. Where the prose states
the number, ``prose`` is the text the lecture's markdown must contain, so that
prose and output cannot drift apart again.

The notebooks are executed once per test session by the ``executed_lecture``
fixture (``tests/conftest.py``), shared with ``tests/notebooks/test_notebooks.py`` and
``tests/course/release/test_site.py``.
"""

import math
import re
from collections import namedtuple
from pathlib import Path

import nbformat
import pytest

ROOT = Path(__file__).resolve().parents[2]
AT_LEAST = (0.0, math.inf)  # tolerance of a lower bound: value >= expected

Claim = namedtuple("Claim", "lecture claim pattern expected tolerance prose")

NUMBER = r"([-+]?\d+(?:\.\d*)?(?:e[-+]?\d+)?)"

CLAIMS = [
    # Lecture 1: measured orders, Euler's energy factor, the spiral of the animation
    Claim("01_state_and_steppers", "Euler's measured order on the oscillator",
          rf"^euler\s+1\s+{NUMBER}",
          1.04, 0.005, "Euler 1.04"),
    Claim("01_state_and_steppers", "symplectic Euler's measured order",
          rf"^symplectic_euler\s+1\s+{NUMBER}",
          1.01, 0.005, "symplectic Euler 1.01"),
    Claim("01_state_and_steppers", "velocity Verlet's measured order",
          rf"^verlet\s+2\s+{NUMBER}",
          2.00, 0.005, "velocity Verlet 2.00"),
    Claim("01_state_and_steppers", "RK4's measured order",
          rf"^rk4\s+4\s+{NUMBER}",
          4.01, 0.005, "RK4 4.01"),
    Claim("01_state_and_steppers", "Euler multiplies the energy by 1 + (omega h)^2 per step",
          rf"every step x{NUMBER}; \(omega h\)\^2 \+ 1 = 1\.010966",
          1.010966, 5e-7, None),
    Claim("01_state_and_steppers", "Euler's particles end at 2.5 times their radius",
          rf"^euler\s+mean r\(t_end\) / r\(0\) = {NUMBER}",
          2.548, 5e-4, "about 2.5 times"),
    Claim("01_state_and_steppers", "a run of velocity Verlet pays n + 1 force evaluations for n steps",
          rf"^verlet\s+{NUMBER} force evaluations for 100 steps",
          101, 0, "$n + 1$ evaluations"),
    Claim("01_state_and_steppers", "Euler acts like a damper -m ln(1 + (omega h)^2) / h = -0.1041 kg/s",
          rf"^euler\s+d_eff = {NUMBER} kg/s -0\.1041",
          -0.1041, 5e-4, None),
    Claim("01_state_and_steppers", "RK4 is stable on the imaginary axis up to omega h = 2 sqrt 2",
          rf"^rk4\s+\|R\(0\.5 i\)\| = \S+ \|R\(i omega h\)\| <= 1 up to omega h = {NUMBER}",
          2.828, 1e-3, "2\\sqrt2 = 2.83"),
    Claim("01_state_and_steppers", "Euler's blob grows by (det S)^20 = 1.09^20 in area",
          rf"^euler\s+area ratio {NUMBER}",
          1.09**20, 1e-9, None),
    Claim("01_state_and_steppers", "symplectic Euler keeps the blob's area",
          rf"^symplectic_euler\s+area ratio {NUMBER}",
          1.0, 1e-9, None),
    Claim("01_state_and_steppers", "step doubling beats fixed RK4 steps at equal work on an eccentric orbit",
          rf"the adaptive run ends {NUMBER} times closer",
          1000, AT_LEAST, None),
    Claim("01_state_and_steppers", "step doubling's steps at the passage are over 100 times shorter",
          rf"largest accepted step / smallest: {NUMBER}",
          100, AT_LEAST, "more than a hundred times shorter"),
    # Lecture 2: damping, momentum, the bucket grid
    Claim("02_forces", "measured relaxation time for d = 0.1 kg/s",
          rf"^\s+0\.1\s+20\.000\s+{NUMBER}",
          20.0, 1e-3, None),
    Claim("02_forces", "terminal speed m g / d at d = 25 kg/s",
          rf"^\s+25\.0\s+\S+\s+{NUMBER}\s+0\.392",
          0.392, 5e-4, "0.39 m/s"),
    Claim("02_forces", "the sweep's fastest settling",
          rf"fastest settling: d = {NUMBER} kg/s",
          1.41, 5e-3, "$d = 1.41$ kg/s"),
    Claim("02_forces", "N-body momentum conserved to round-off",
          rf"largest momentum change: {NUMBER} kg m/s",
          0.0, 1e-14, None),
    Claim("02_forces", "mean fraction of the 3 x 3 block's candidates that are neighbours",
          rf"whose block lies inside the box: {NUMBER}% of the candidates",
          35.0, 1.0, "35% of the candidates"),
    Claim("02_forces", "bucket grid more than 10 times faster than all pairs at N = 2000 (timing)",
          rf"N =  2000: all pairs .* ratio\s+{NUMBER}",
          10.0, AT_LEAST, None),
    Claim("02_forces", "explicit Euler's effective damping at d = 0 is -h k (exactly -ln(1 + h^2 k/m)/h)",
          rf"^\s+0\.0\s+{NUMBER}\s+-0\.100",
          -0.0995, 5e-5, "$\\mp 0.0995$"),
    Claim("02_forces", "backward Euler's effective damping at d = 0 is +h k",
          rf"^\s+0\.0\s+\S+\s+-0\.100\s+{NUMBER}",
          0.0995, 5e-5, None),
    # Lecture 3: the overshooting fixes and the bowl
    Claim("03_collisions", "projection's elastic ball climbs to 1.48 m in 20 bounces",
          rf"project\s+eps = 1, height after 20 bounces: {NUMBER} m",
          1.484, 5e-4, "1.48 m"),
    Claim("03_collisions", "backtracking keeps the restitution ratio eps^2 = 0.64",
          rf"^backtrack\s+0\.80\s+6\s+\S+\s+{NUMBER} to",
          0.64, 5e-5, "0.6400"),
    Claim("03_collisions", "projection gains exactly g d per bounce",
          rf"^project\s*: 10 bounces, .* largest \|dE - g d\| = {NUMBER} J/kg",
          0.0, 1e-12, None),
    Claim("03_collisions", "projection's error halves with the step (first order)",
          rf"^\s+0\.005\s+\S+\s+{NUMBER}",
          2.0, 0.2, "ratios about 2"),
    Claim("03_collisions", "the bowl keeps less than 1% of the mechanical energy",
          rf"mechanical energy kept: {NUMBER}",
          0.0, (0.0, 0.01), "more than 99%"),
    Claim("03_collisions", "naive restitution: the resting ball is off the floor on most steps",
          rf"^1 ball\(s\),\s+naive: .* no floor contact in\s+{NUMBER}%",
          50, AT_LEAST, None),
    Claim("03_collisions", "resting contact: the stack of four comes to rest",
          rf"^4 ball\(s\), resting: largest speed {NUMBER} m/s",
          0.0, (0.0, 1e-12), None),
    Claim("03_collisions", "resting contact: the floor carries the stack's weight 4 m g",
          rf"^4 ball\(s\), resting: .* floor force\s+{NUMBER} \+- ",
          4 * 9.81, 5e-4, None),
    # Lecture 4: emitters
    Claim("04_emitters_and_rendering", "the slide's literal t_last = t emits 6.67/s for 10/s",
          rf"i\.e\. {NUMBER} per second instead of 10",
          6.67, 5e-3, "6.67 per second"),
    Claim("04_emitters_and_rendering", "the carried emitter never misses a particle",
          rf"largest \|N - floor\(rate t\)\| over all steps = {NUMBER}",
          0, 0, None),
    Claim("04_emitters_and_rendering", "worst literal rate 5.13/s",
          rf"worst: {NUMBER} particles/s",
          5.13, 5e-3, "5.13"),
    Claim("04_emitters_and_rendering", "staggered births 3.1 cm apart",
          rf"staggered: 200 particles, gaps {NUMBER} to",
          0.0314, 5e-5, "3.1 cm"),
    Claim("04_emitters_and_rendering", "the Genesis ring made floor(150 x 2) systems",
          rf"secondary systems made: {NUMBER}",
          300, 0, None),
    Claim("04_emitters_and_rendering", "the fountain holds about rate x mean lifetime = 200",
          rf"alive after 1\.3 s: mean {NUMBER}",
          200.0, 5.0, None),
    Claim("04_emitters_and_rendering", "additive blending does not depend on the drawing order",
          rf"change with the order: additive {NUMBER}",
          0.0, (0.0, 1e-12), None),
    Claim("04_emitters_and_rendering", "'over' blending does depend on it",
          rf"change with the order: additive \S+, over {NUMBER}",
          0.05, AT_LEAST, None),
    # Lecture 5: flocks and crowds
    Claim("05_flocks", "with a view half-angle of pi/2, half of the sightings are one-way",
          rf"phi = 0\.50 pi: .* one-way\s+{NUMBER}%",
          50.0, 1.0, None),
    Claim("05_flocks", "alignment alone: polarization 0.947",
          rf"^alignment\s+{NUMBER}",
          0.947, 5e-4, "0.947"),
    Claim("05_flocks", "all three rules: polarization 0.997",
          rf"^separation \+ alignment \+ cohesion\s+{NUMBER}",
          0.997, 5e-4, "0.997"),
    Claim("05_flocks", "every boid of the crowd reaches the goal",
          rf"goal and rock: {NUMBER}% reached the goal",
          100, 0, None),
    Claim("05_flocks", "no boid goes through the rock",
          rf"goal and rock: .*?{NUMBER} boids went through it",
          0, 0, "none enters the rock"),
    Claim("05_flocks", "the closest boid stays outside the rock (radius 2 m)",
          rf"goal and rock: .*closest to the rock's centre {NUMBER} m",
          2.0, AT_LEAST, "2.82 m"),
    Claim("05_flocks", "the separation weight is in m^2/s^2: scaled by lambda^2 in cm it gives lambda times a",
          rf"^separation: largest \|a_cm / lambda - a_m\| = {NUMBER}",
          0.0, (0.0, 1e-12), None),
    # Lecture 6: mass-spring models
    Claim("06_mass_spring", "hanging string's stretch as statics predicts",
          rf"measured stretch {NUMBER} mm",
          37.278, 5e-4, None),
    Claim("06_mass_spring", "physical scaling: the same stretch at n = 40",
          rf"n = 40: stretch {NUMBER} mm",
          49.050, 5e-4, None),
    Claim("06_mass_spring", "hair droop / beam theory at 41 particles",
          rf"measured / beam theory = \[.* {NUMBER}\]",
          0.9506, 5e-5, None),
    Claim("06_mass_spring", "no shear springs: the curtain tilts by arctan(a / g)",
          rf"no shear springs: the bottom row tilts by {NUMBER} degrees",
          17.0, 0.1, None),
    Claim("06_mass_spring", "the pins carry the weight M g = 1.962 N",
          rf"sum of the pin forces: \[\S+\s+\S+\s+{NUMBER}\] N",
          1.962, 5e-4, None),
    Claim("06_mass_spring", "momentum balance with the pin forces closes",
          rf"largest \|dP/dt - \(M g \+ sum R\)\| = {NUMBER} N",
          0.0, 1e-9, None),
    Claim("06_mass_spring", "Provot's wind on the billowed sail is less than on the flat sheet (2 N)",
          rf"Provot's surface wind: .* force on the billowed sail {NUMBER} N",
          1.887, 0.01, None),
    Claim("06_mass_spring", "Provot's wind does not push a sheet edge-on to it",
          rf"Provot's surface wind: .* edge-on to the wind {NUMBER} N",
          0.0, 0.0, None),
    # Lecture 7: stiffness, Provot, sparsity, solving the implicit step
    Claim("07_stiffness_provot_implicit", "h_max falls like k^(-1/2)",
          rf"symplectic_euler: fitted slope {NUMBER}",
          -0.5, 5e-4, "$-1/2$"),
    Claim("07_stiffness_provot_implicit", "RK4's measured omega h_max",
          rf"rk4: fitted slope \S+, measured omega h_max = \[{NUMBER}",
          2.84, 5e-3, "2.84"),
    Claim("07_stiffness_provot_implicit", "soft curtain: 45% strain after 200 steps",
          rf"soft springs: largest strain \d+% during the fall, {NUMBER}% after 200 steps",
          45, 0.5, None),
    Claim("07_stiffness_provot_implicit", "Provot's curtain: 10.4% after 200 steps",
          rf"with the constraint: {NUMBER}% after 200 steps",
          10.4, 0.05, None),
    Claim("07_stiffness_provot_implicit", "one linearized solve per step gains 11% of M g H",
          rf"Baraff-Witkin, one solve \(paper\)\s+1\.00 solves\s+{NUMBER}%",
          11.17, 0.05, "11% of $MgH$"),
    Claim("07_stiffness_provot_implicit", "Liu's 10 iterations hold the falling cloth back (0.17 m at 0.5 s)",
          rf"prefactored, 10 iterations \(Liu\)\s+10 iterations\s+\S+%\s+\S+%\s+\S+%\s+{NUMBER} m",
          0.167, 0.005, "0.17 m"),
    Claim("07_stiffness_provot_implicit", "the 48 x 48 cloth's K is 0.55% full",
          rf"48 x 48 cloth: .* fill K\.nnz / \(3n\)\^2 = {NUMBER}%",
          0.55, 5e-3, "0.55%"),
    Claim("07_stiffness_provot_implicit", "at most 39 nonzeros per row of K",
          rf"48 x 48 cloth: .* nonzeros per row \d+ to {NUMBER}",
          39, 0, "39 nonzeros"),
    Claim("07_stiffness_provot_implicit", "the library's Jacobi variant of Provot takes 44 passes per step",
          rf"projection passes per step: {NUMBER} on average",
          44, 0.5, "44 Jacobi passes"),
    Claim("07_stiffness_provot_implicit", "the squeezed cloth's unclamped A has dozens of negative eigenvalues",
          rf"clamp=False: smallest eigenvalue of A \S+ kg, {NUMBER} negative",
          24, AT_LEAST, None),
    Claim("07_stiffness_provot_implicit", "clamped, A is positive definite on the squeezed cloth",
          rf"clamp= True: smallest eigenvalue of A \S+ kg, {NUMBER} negative",
          0, 0, None),
    Claim("07_stiffness_provot_implicit", "the prefactored solver beats compiled explicit springs at h = 1/60 s",
          rf"prefactored at h = 1/60 s: .*, {NUMBER}x as fast$",
          1.0, AT_LEAST, None),
    Claim("07_stiffness_provot_implicit", "and at h = 1/10 s by more than at 1/60 s",
          rf"prefactored at h = 1/10 s: .*, {NUMBER}x as fast$",
          2.0, AT_LEAST, None),
    Claim("07_stiffness_provot_implicit", "h_max is a fixed fraction of dx / c (the CFL condition)",
          rf"h_max / \(dx / c\):\s+\[{NUMBER}",
          0.97, 0.01, None),
    Claim("07_stiffness_provot_implicit", "the flexion springs' bending energy falls like n^-4",
          rf"fitted slope of the bending energy against n: {NUMBER}",
          -4.22, 0.02, None),
    # Lecture 8: Lagrange multipliers, PBD and XPBD stiffness, small steps
    Claim("08_constraints", "the multiplier pendulum's period at 120 degrees within 1e-4 of the elliptic integral",
          rf"exact period \S+ s, measured \S+ s, relative error {NUMBER}",
          0.0, (0.0, 1e-4), None),
    Claim("08_constraints", "at 120 degrees the period is 1.373 times the small-angle one",
          rf"the exact one is {NUMBER} times longer",
          1.373, 5e-4, "1.373 times the small-angle period"),
    Claim("08_constraints", "XPBD's curtain at one iteration: 28.94 N/m for springs of 30",
          rf"XPBD effective stiffness \(N/m\): \[{NUMBER}",
          28.94, 5e-3, "28.94 N/m at one iteration"),
    Claim("08_constraints", "PBD's curtain at 50 iterations: 866.6 N/m",
          rf"PBD effective stiffness \(N/m\): \[\s*\S+\s+\S+\s+{NUMBER}\]",
          866.6, 0.05, "866.6 N/m at 50"),
    Claim("08_constraints", "XPBD varies by less than 5% from 1 to 50 iterations",
          rf"XPBD varies by {NUMBER}% from 1 to 50 iterations",
          3.7, 0.05, "a variation of 3.7%"),
    Claim("08_constraints", "20 substeps of one iteration: largest strain 1.14%",
          rf"20 substeps x 1 iter\.\s+{NUMBER}%",
          1.14, 5e-3, "stretch it to 1.14%"),
    Claim("08_constraints", "64 x 64 cloth: 23938 rods on 12288 coordinates",
          rf"64 x 64 cloth: {NUMBER} rods on 12288 coordinates",
          23938, 0, None),
    Claim("08_constraints", "the 8 x 8 cloth's J W J^T is singular",
          rf"so J W J\^T has {NUMBER} zero eigenvalues",
          182, 0, None),
    Claim("08_constraints", "PBD corrected for the iterations varies by less than 1% from 1 to 50",
          rf"corrected PBD varies by {NUMBER}% from 1 to 50 iterations",
          0.07, 0.02, None),
    Claim("08_constraints", "converged XPBD on one step loses what backward Euler at h = 1/60 s loses",
          rf"energy lost, XPBD 1 x 200 / backward Euler at 1/60 s: {NUMBER}",
          1.0, 0.01, "within a per cent"),
    Claim("08_constraints", "20 substeps x 1 lose about what backward Euler at h = 1/1200 s loses",
          rf"energy lost, XPBD 20 x 1 / backward Euler at 1/1200 s: {NUMBER}",
          0.967, 0.01, None),
    # Lecture 9: the mesh, the exact test, particles against Bridson et al., cost and step
    Claim("09_cloth_collisions", "Euler's formula of the grid mesh: V - E + F = 1",
          rf"V - E \+ F = \d+ - \d+ \+ \d+ = {NUMBER}",
          1, 0, "$V - E + F = 1$"),
    Claim("09_cloth_collisions", "the grid folded through itself: 45 = 3 (n - 1) crossing pairs",
          rf"crossing pairs: {NUMBER}, expected 3 \(n - 1\) = 45",
          45, 0, "finds the 45 crossings"),
    Claim("09_cloth_collisions", "particle self-collision at 0.25 dx lets the folded sheet cross itself",
          rf"particles, d = 0\.25 dx: at most\s+{NUMBER} crossing pairs",
          1, AT_LEAST, None),
    Claim("09_cloth_collisions", "ClothCollisions at 0.25 dx: no crossing pair on the bar",
          rf"ClothCollisions, d = 0\.25 dx: at most {NUMBER} crossing pairs",
          0, 0, None),
    Claim("09_cloth_collisions", "ClothCollisions: no crossing pair while the roller winds the cloth up",
          rf"^ClothCollisions: at most\s+{NUMBER} crossing pairs",
          0, 0, None),
    Claim("09_cloth_collisions", "cost per step grows at most linearly with the triangles",
          rf"fitted slope of the time per step against the triangles: {NUMBER}",
          1.0, (1.0, 0.3), None),
    Claim("09_cloth_collisions", "the thrown sheet: proximity only safe up to 10 ms, all stages up to 25 ms",
          rf"largest safe step: proximity only 10 ms, all stages {NUMBER} ms",
          25, 0, "proximity only up to 10 ms, all stages up to 25 ms"),
    # Appendix A1: the periodic liquid against NIST's table, within 3 combined standard errors of a 20-unit
    # run (ours about 0.009 and 0.045, NIST's 0.0024 and 0.0136): the trajectory is chaotic, so another
    # machine's round-off gives other means, as likely as these
    Claim("A1_lennard_jones_liquid", "periodic LJ liquid: U/N within 3 combined SE of NIST's -6.0305",
          rf"U/N: ours {NUMBER} \+- ",
          -6.0305, 0.03, "$U/N = -6.0305 \\pm 0.0024$"),
    Claim("A1_lennard_jones_liquid", "periodic LJ liquid: pressure within 3 combined SE of NIST's 1.2660",
          rf"p: ours {NUMBER} \+- ",
          1.2660, 0.14, "$p^* = 1.2660 \\pm 0.0136$"),
    # Appendix A2: the compiled loop computes the NumPy forces to round-off
    Claim("A2_memory_traffic", "the compiled spring loop gives the NumPy forces to round-off",
          rf"largest difference: {NUMBER} of the largest force",
          0.0, (0.0, 1e-12), None),
    # Appendix A3: exact signs
    Claim("A3_exact_predicates", "plain float64 gets more than a quarter of 2000 near-coplanar signs wrong",
          rf"differs from the exact one in {NUMBER} of 2000",
          500, AT_LEAST, None),
    Claim("A3_exact_predicates", "no plain sign above Shewchuk's bound is wrong",
          rf"below the bound, {NUMBER} above it",
          0, 0, None),
]


def _path(lecture):
    return ROOT / "lectures" / f"{lecture}.ipynb"


def printed_text(nb):
    """Stream output and ``text/plain`` results of all code cells, concatenated."""
    parts = []
    for cell in nb.cells:
        for out in cell.get("outputs", []) if cell.cell_type == "code" else []:
            if out.get("output_type") == "stream":
                parts.append(out.get("text", ""))
            elif "text/plain" in out.get("data", {}):
                parts.append(out["data"]["text/plain"] + "\n")
    return "".join(parts)


def _holds(value, expected, tolerance):
    below, above = tolerance if isinstance(tolerance, tuple) else (tolerance, tolerance)
    return expected - below <= value <= expected + above


def _ids(claims):
    return [f"{c.lecture[:2]}-{re.sub(r'[^a-z0-9]+', '-', c.claim.lower()).strip('-')[:50]}" for c in claims]


# claims per notebook: a lecture states its key numbers, an appendix its few; lectures 1, 7 and 8 carry more
# since issue 46 (lecture 1: stability regions, the step map's area, adaptive steps and the work of Verlet;
# lecture 7: the spring Jacobian with and without its definiteness fix, the CFL step and flexion bending;
# lecture 8: XPBD's energy against backward Euler, PBD's iteration correction and the over-constrained cloth);
# lecture 7 two more since issue 49 (the prefactored solver against explicit springs at h = 1/60 s and 1/10 s)
CLAIM_BOUNDS = {"lecture": (3, 15), "appendix": (1, 8)}


def test_every_lecture_and_appendix_has_its_claims():
    """The table names every lecture of lectures/ with 3 to 15 claims and every appendix with 1 to 8, each
    with a number group."""
    notebooks = sorted(p.stem for p in (ROOT / "lectures").glob("[0-9A][0-9]_*.ipynb"))
    counts = {name: sum(c.lecture == name for c in CLAIMS) for name in notebooks}
    assert set(c.lecture for c in CLAIMS) <= set(notebooks), "a claim names a lecture that does not exist"
    for name, k in counts.items():
        low, high = CLAIM_BOUNDS["appendix" if name.startswith("A") else "lecture"]
        assert low <= k <= high, (name, k)
    assert all(re.compile(c.pattern).groups >= 1 for c in CLAIMS)


@pytest.mark.parametrize("claim", CLAIMS, ids=_ids(CLAIMS))
def test_the_lecture_prints_its_claim(claim, executed_lecture):
    """The executed lecture prints the claimed number, within the claim's tolerance."""
    text = printed_text(executed_lecture(_path(claim.lecture)))
    match = re.search(claim.pattern, text, flags=re.M)
    assert match, (f"{claim.lecture}: claim '{claim.claim}': nothing printed matches {claim.pattern!r}")
    value = float(match.group(1))
    assert _holds(value, claim.expected, claim.tolerance), (
        f"{claim.lecture}: claim '{claim.claim}': printed {match.group(0).strip()!r}, i.e. {value:g}, "
        f"expected {claim.expected:g} within {claim.tolerance}")


PROSE = [c for c in CLAIMS if c.prose]


@pytest.mark.parametrize("claim", PROSE, ids=_ids(PROSE))
def test_the_prose_states_the_printed_claim(claim):
    """The lecture's markdown states the claim with the number its cells print."""
    nb = nbformat.read(_path(claim.lecture), as_version=4)
    prose = " ".join(" ".join(cell.source.split()) for cell in nb.cells if cell.cell_type == "markdown")
    assert claim.prose in prose, f"{claim.lecture}: claim '{claim.claim}': the markdown does not say {claim.prose!r}"
