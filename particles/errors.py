"""Exceptions raised by the library.

Bad input raises :class:`ValueError` (or :class:`TypeError`) naming the argument
and what was expected. The two classes here are for things that go wrong *during*
a computation that was given valid input.
"""

__all__ = ["SimulationDiverged", "ConvergenceError"]


class SimulationDiverged(RuntimeError):
    """The state blew up (inf, NaN, or a trillion-fold growth) during a simulation.

    Raised by :func:`particles.integrators.integrate`,
    :meth:`particles.ParticleSystem.run` and the other ``run`` and ``step``
    methods instead of returning NaNs. The growth rule (``blowup``, default
    ``1e12``) catches an unstable run before it overflows; a problem whose
    true solution grows that much passes ``blowup=None``.

    Attributes
    ----------
    step : int
        Index of the step that produced the non-finite state (1 = first step).
    t : float
        Time at the start of that step, in seconds.
    h : float
        Time step used, in seconds.
    method : str
        Name of the stepper.
    """

    def __init__(self, step, t, h, method, detail=""):
        self.step, self.t, self.h, self.method = step, t, h, method
        message = (
            f"the simulation diverged at step {step} (t = {t:.6g} s): the state "
            f"blew up with method {method!r} and h = {h:.6g} s. The likely "
            f"cause is a time step above the stability limit of {method!r} for this "
            "system (stiff springs, strong forces or too little damping); reduce h, "
            "add damping, or use an implicit method."
        )
        if detail:
            message += " " + detail
        super().__init__(message)


class ConvergenceError(RuntimeError):
    """An iterative solver (Newton, conjugate gradients) did not converge."""
