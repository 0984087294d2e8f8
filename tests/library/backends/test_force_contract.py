"""The force contract (tests/library/forces/test_force_contract.py) on each backend.

Every check of the contract runs again with every object on the NumPy and the
numba backend, and every force of it is compared between the two to 1e-12
relative. Tests that need numba are skipped when the extra ``[fast]`` is not
installed.
"""

import pytest

from particles import backends

from ..forces import test_force_contract as contract
from .helpers import _close, needs_numba

BACKEND_NAMES = [pytest.param("numpy"), pytest.param("numba", marks=needs_numba)]

# the force contract, run again with every object on the backend
CONTRACT = [contract.test_inputs_are_not_modified, contract.test_add_to_adds_in_place_with_the_right_shape_and_dtype,
            contract.test_forces_between_particles_conserve_momentum,
            contract.test_force_is_minus_the_gradient_of_its_potential_energy,
            contract.test_declared_independence_of_velocity_and_time_holds]


def _contract_params():
    out = []
    for check in CONTRACT:  # each check of the contract, on the cases it applies to
        chosen = [m for m in check.pytestmark if m.name == "parametrize"][0].args[1]
        out += [pytest.param(check, *p.values, id=f"{check.__name__[5:]}-{p.id}") for p in chosen]
    return out


@pytest.mark.parametrize("backend", BACKEND_NAMES)
@pytest.mark.parametrize("check, case, d", _contract_params())
def test_the_force_contract_holds_on_each_backend(check, case, d, backend):
    """Every check of the force contract passes with every object on this backend."""
    with backends.using(backend):
        check(case, d)


@needs_numba
@pytest.mark.parametrize("case, d", contract._params())
def test_numba_forces_agree_with_numpy_on_every_contract_case(case, d):
    """Each contract force on numba equals its NumPy value to 1e-12 relative (with velocities and masses)."""
    x, v, m, t = contract._state(d)
    out = {}
    for backend in ("numpy", "numba"):
        with backends.using(backend):
            force = case.make(x)
            out[backend] = force(x, v, t, m), getattr(force, "last_virial", 0.0)
    _close(out["numpy"][0], out["numba"][0])
    assert out["numba"][1] == pytest.approx(out["numpy"][1], rel=1e-12, abs=1e-300)
