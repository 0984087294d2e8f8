"""The benchmark scripts' set-ups, built without timing anything (speed is measured in bench/, never here)."""

import re
import sys
from pathlib import Path

import numpy as np
import pytest

BENCH = Path(__file__).resolve().parents[2] / "bench"


@pytest.fixture(scope="module")
def harness():
    """bench/bench_warp_harness.py, imported as a module (it imports neither Warp nor Taichi when loaded)."""
    sys.path.insert(0, str(BENCH))
    try:
        import bench_warp_harness
    finally:
        sys.path.remove(str(BENCH))
    return bench_warp_harness


def _stated(doc):
    """The topology lines of the docstring: {n: counts}."""
    line = re.compile(r"^\s*(\d+)\^2: (\d+) particles, (\d+) springs \((\d+) structural, (\d+) shear, "
                      r"(\d+) flexion\), (\d+) pinned$", re.M)
    return {int(n): dict(zip(("particles", "springs", "structural", "shear", "flexion", "pinned"), map(int, rest)))
            for n, *rest in line.findall(doc)}


def test_the_warp_harness_states_the_topology_of_every_size(harness):
    """The docstring of bench_warp_harness.py gives the topology of each of its sizes, 32^2 to 128^2."""
    assert sorted(_stated(harness.__doc__)) == list(harness.SIZES) == [32, 64, 128]


@pytest.mark.parametrize("n", [32, 64, 128])
def test_the_warp_harness_builds_the_counts_its_docstring_states(harness, n):
    """The scene of each size has the particles, springs by kind and pins that the docstring states."""
    c = harness.scene(n)
    stated = _stated(harness.__doc__)[n]
    built = harness.topology(c)
    assert built == {key: stated[key] for key in built}
    assert sum(len(s) for s in c.springs.values()) == stated["springs"] == harness._springs(n)
    assert c.pinned.tolist() == [0, n - 1]                   # the two corners of the first row


@pytest.mark.parametrize("n", [5, 32])
def test_the_warp_harness_springs_join_the_stencil_neighbours(harness, n):
    """Each kind of spring joins exactly the grid neighbours of Warp's layout, at rest in the flat sheet."""
    c = harness.scene(n)
    for kind, springs in c.springs.items():
        built = {tuple(sorted(p)) for p in springs.indices.tolist()}
        stencil = {tuple(sorted(p)) for p in harness.stencil_pairs(n, kind).tolist()}
        assert built == stencil and len(built) == len(springs), kind
        assert np.allclose(springs.rest_length, springs.lengths(c.X[:, 0]))
    assert np.all(c.X[:, 0, 2] == 0.0)                       # flat, in the x-y plane
    assert np.allclose(np.diff(np.sort(np.unique(c.X[:, 0, 0]))), harness.SPACING)


def test_the_warp_harness_parameters_are_warps(harness):
    """Masses, stiffness, damping, gravity and the step are those of Warp's cloth benchmark."""
    c = harness.scene(8)
    assert np.all(c.m == 0.1)
    for springs in c.springs.values():
        assert np.all(springs.k == 1000.0) and np.all(springs.kd == 10.0)
    a = c.derivative(c.state(), 0.0)[:, 1]
    free = np.setdiff1d(np.arange(c.n), c.pinned)
    assert np.allclose(a[free], [0.0, 0.0, -9.81]) and np.all(a[c.pinned] == 0.0)
    assert harness.H * harness.SUBSTEPS * harness.FPS == pytest.approx(1.0)
    assert harness.FRAMES * harness.SUBSTEPS == 960


@pytest.mark.parametrize("script", sorted(p.name for p in BENCH.glob("bench_*.py")))
def test_every_bench_script_loads(script, monkeypatch):
    """Each script's imports resolve (a moved test folder once left bench_grading.py unable to start).

    What a script changes when it loads (its folders in ``sys.path``, ``OPENBLAS_NUM_THREADS``) is undone
    after, so that the tests that run next in this process see neither."""
    import importlib.util
    import os

    monkeypatch.setattr(sys, "path", [str(BENCH), *sys.path])
    environment = dict(os.environ)
    try:
        spec = importlib.util.spec_from_file_location(f"_loaded_{script[:-3]}", BENCH / script)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    finally:
        for name in set(os.environ) - set(environment):  # a loop over the few variables a script set
            del os.environ[name]
        os.environ.update(environment)
    assert callable(getattr(module, "main", None)), f"{script} has no main()"


def test_no_bench_script_imports_from_the_tests():
    """The benches stand alone: no script or helper of bench/ puts tests/ on its path or imports from it."""
    reaching = []
    for path in sorted(BENCH.glob("*.py")):
        text = path.read_text(encoding="utf-8")
        if re.search(r"^\s*(from|import)\s+tests\b", text, re.M) or re.search(r"sys\.path\.\w+\(.*[\"']tests[\"']", text):
            reaching.append(path.name)
    assert reaching == []

