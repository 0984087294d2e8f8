"""The discretization study (particles.studies.discretization): physical scaling holds under refinement."""

import pytest

from particles.studies import discretization


def test_discretization_study_small():
    """Physical scaling: same sag and period at 6 and 12 per side, h_max ~ dx; naive: neither."""
    study = discretization.discretization_study(resolutions=(6, 12), reference=6)
    phys, naive = study["physical"], study["naive"]
    assert phys["sag"][1] == pytest.approx(phys["sag"][0], rel=0.02)
    assert phys["period"][1] == pytest.approx(phys["period"][0], rel=0.05)
    assert naive["sag"][1] > 2 * naive["sag"][0]
    assert naive["period"][1] > 1.5 * naive["period"][0]
    assert phys["h_exponent"] == pytest.approx(1.0, abs=0.1)
    assert abs(naive["h_exponent"]) < 0.1


@pytest.mark.parametrize("call, name", [
    (lambda: discretization.hanging_cloth(2, "physical"), "n"),
    (lambda: discretization.bounce_period(discretization.hanging_cloth(4, "physical"), periods=0), "periods"),
    (lambda: discretization.bounce_period(discretization.hanging_cloth(4, "physical"), safety=1.5), "safety"),
], ids=["n", "periods", "safety"])
def test_discretization_bad_arguments_are_named(call, name):
    """A too small cloth, no periods, a step past the stability limit are named."""
    with pytest.raises(ValueError, match=f"^{name} must"):
        call()
