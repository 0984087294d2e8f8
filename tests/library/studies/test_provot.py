"""The Provot study (particles.studies.provot): the constraint holds the curtain's strain at 10%."""

import pytest

from particles.studies import provot


def test_provot_study_small():
    """Soft springs stretch several times past 10%; the constraint holds them at 10% + tolerance."""
    study = provot.provot_study(n=8, steps=200)
    assert study["strain"]["free"].max() > 0.3
    assert study["strain"]["provot"].max() <= 0.1 + study["tol"] + 1e-12
    assert len(study["iterations"]) == 200


@pytest.mark.parametrize("kwargs, name", [
    ({"h": -1.0}, "h"), ({"h": 0.0}, "h"), ({"steps": 0}, "steps"), ({"n": 2}, "n"), ({"k": -30.0}, "k"),
    ({"max_strain": 0.0}, "max_strain"), ({"every": 0}, "every"),
])
def test_provot_study_bad_arguments_are_named(kwargs, name):
    """provot_study names its own argument (h, not the integrator's t1)."""
    with pytest.raises(ValueError, match=f"^{name} must"):
        provot.provot_study(**kwargs)
