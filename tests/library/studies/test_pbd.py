"""The PBD study (particles.studies.pbd): XPBD's stiffness does not depend on iterations, PBD's does."""

import pytest

from particles.studies import pbd


def test_xpbd_stiffness_does_not_depend_on_iterations_pbd_does():
    """On lecture 7's curtain XPBD's effective stiffness varies < 5% from 1 to 50 iterations, PBD's > 2x; PBD
    with the iteration-corrected stiffness starts where PBD does and varies < 5% too."""
    study = pbd.stiffness_study(iterations=(1, 50), steps=(), corrected=True)
    xpbd, pbd_k = study["by_iterations"]["xpbd"], study["by_iterations"]["pbd"]
    assert max(xpbd) / min(xpbd) < 1.05 and all(abs(k / 30.0 - 1.0) < 0.05 for k in xpbd)
    assert pbd_k[1] / pbd_k[0] > 2.0
    fixed = study["by_iterations"]["pbd_corrected"]
    assert fixed[0] == pytest.approx(pbd_k[0], rel=1e-9) and max(fixed) / min(fixed) < 1.05


@pytest.mark.parametrize("make, name", [
    (lambda: pbd.effective_stiffness(10.0, pbd.spring_sags([30.0, 60.0], n=4)), "sag"),
])
def test_bad_input_names_the_argument(make, name):
    """Bad arguments raise ValueError naming the argument."""
    with pytest.raises(ValueError, match=name):
        make()
