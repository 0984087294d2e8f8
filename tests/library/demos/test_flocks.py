"""The flock demo (particles.demos.flocks): the boids align."""

from particles.demos import run_demo


def test_flock_aligns():
    """The flock demo measures its own polarization, which rises."""
    data = run_demo("flock")
    before, after = (float(p) for p in data.info["polarization"].split(" -> "))
    assert before < 0.2 and after > 0.9
