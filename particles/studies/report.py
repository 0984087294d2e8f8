"""Write each study's figure (PNG and SVG) and table (CSV): ``particles study NAME``."""

import csv
import time
from pathlib import Path

import numpy as np

__all__ = ["STUDIES", "write_study", "write_table"]


def _save(fig, out, name):
    import matplotlib.pyplot as plt

    paths = []
    for ext in ("png", "svg"):
        path = out / f"{name}.{ext}"
        fig.savefig(path, dpi=120, bbox_inches="tight")
        paths.append(path)
    plt.close(fig)
    return paths


def write_table(out, name, rows):
    """Write a list of dicts as the CSV table ``out/name.csv``.

    Parameters
    ----------
    out : str or pathlib.Path
        An existing directory.
    name : str
        File name without the extension.
    rows : list of dict
        One dict per row (at least one), all with the keys of the first, which
        become the header in their order.

    Returns
    -------
    pathlib.Path
        The file written.
    """
    if not isinstance(rows, (list, tuple)) or not rows or not all(isinstance(r, dict) for r in rows):
        raise ValueError(f"rows must be a non-empty list of dicts, got {type(rows).__name__}")
    path = Path(out) / f"{name}.csv"
    with open(path, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return path


def order(out):
    """Convergence orders on three problems with exact solutions."""
    from .order import convergence_study, plot_convergence

    rows, lines = [], []
    for problem in ("harmonic_oscillator", "circle", "projectile_drag"):
        study = convergence_study(problem)
        for m in study["order"]:
            rows.append({"problem": problem, "method": m, "expected_order": study["expected"][m],
                         "observed_order": round(study["order"][m], 3),
                         "error_at_smallest_h": study["error"][m][-1]})
        if problem == "harmonic_oscillator":
            files = _save(plot_convergence(study), out, "order")
            lines += [f"{m:<18} expected {study['expected'][m]}  observed {p:.2f}"
                      for m, p in study["order"].items()]
    return files + [write_table(out, "order", rows)], lines


def stability(out):
    """Largest stable step against stiffness, chains, implicit damping, cost."""
    import matplotlib.pyplot as plt

    from .stability import (chain_max_stable_step, cost_study, damping_factor, plot_stability, stability_study,
                            THEORY_OMEGA_H)

    study = stability_study()
    rows = [{"k": k, "m": study["m"], "method": meth, "h_max_measured": h, "h_max_theory": th}
            for meth in study["h_max"] for k, h, th in zip(study["k"], study["h_max"][meth], study["theory"][meth])]
    for n in (1, 3, 10):
        h = chain_max_stable_step("symplectic_euler", n, 100.0, 1.0)
        theory = THEORY_OMEGA_H["symplectic_euler"] / (2 * 10.0 * np.sin(n * np.pi / (2 * (n + 1))))
        rows.append({"k": 100.0, "m": 1.0, "method": f"symplectic_euler, chain of {n}",
                     "h_max_measured": h, "h_max_theory": theory})
    fig = plt.figure(figsize=(12, 4.5))
    plot_stability(study, fig.add_subplot(1, 2, 1))
    ax = fig.add_subplot(1, 2, 2)
    wh = np.logspace(-2, 1.5, 30)
    ax.semilogx(wh, damping_factor(wh), "o", label="measured")
    ax.semilogx(wh, 1 / np.sqrt(1 + wh**2), "-", label="1 / sqrt(1 + (omega h)^2)")
    ax.set_xlabel("omega h")
    ax.set_ylabel("amplitude kept per step")
    ax.set_title("Implicit Euler: stable at any h, but damped")
    ax.legend(fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    files = _save(fig, out, "stability")
    cost = cost_study()
    files += [write_table(out, "stability", rows), write_table(out, "stability_cost", cost)]
    lines = [f"{meth:<18} slope of h_max vs k: {study['slope'][meth]:+.3f}   "
             f"omega h_max = {study['h_max'][meth][0] * np.sqrt(study['k'][0] / study['m']):.3f}"
             for meth in study["h_max"]]
    lines.append("cost of 1 s at k = 1e8 N/m: " + ", ".join(
        f"{r['method']} {r['evaluations']} evaluations" for r in cost if r["k"] == max(c["k"] for c in cost)))
    return files, lines


def provot(out):
    """The curtain with and without Provot's constraint."""
    from .provot import plot_provot, provot_study

    study = provot_study()
    rows = [{"t": t, "max_strain_soft_springs": a, "max_strain_provot": b}
            for t, a, b in zip(study["t"], study["strain"]["free"], study["strain"]["provot"])]
    files = _save(plot_provot(study), out, "provot") + [write_table(out, "provot", rows)]
    lines = [f"largest strain after 200 steps: soft springs {100 * study['strain']['free'][-1]:.0f}%, "
             f"with the constraint {100 * study['strain']['provot'][-1]:.1f}% "
             f"(at most {100 * study['strain']['provot'].max():.1f}% during the run, "
             f"{study['iterations'].mean():.0f} projection passes per step on average)"]
    return files, lines


def discretization(out):
    """The same cloth at 8, 16 and 32 particles per side."""
    from .discretization import discretization_study, plot_discretization

    study = discretization_study()
    rows = []
    for scaling in ("naive", "physical"):
        d = study[scaling]
        for n, dx, sag, period, h in zip(study["n"], study["spacing"], d["sag"], d["period"], d["h_max"]):
            rows.append({"scaling": scaling, "n": n, "spacing": dx, "sag": sag, "bounce_period": period,
                         "h_max_symplectic_euler": h})
    files = _save(plot_discretization(study), out, "discretization") + [write_table(out, "discretization", rows)]
    lines = [f"{scaling:<9} sag (mm) {np.round(1000 * study[scaling]['sag'], 2).tolist()}  period (s) "
             f"{np.round(study[scaling]['period'], 3).tolist()}  h_max ~ dx^{study[scaling]['h_exponent']:.2f}"
             for scaling in ("naive", "physical")]
    return files, lines


def bounce(out):
    """A dropped ball: restitution, and projection against backtracking."""
    from .bounce import bounce_study, format_bounce_table, plot_bounce_study

    study = bounce_study()
    rows = [{"method": m, "restitution": e, "bounce": k, "height": hk}
            for (m, e), heights in study["heights"].items() for k, hk in enumerate(heights)]
    files = _save(plot_bounce_study(study), out, "bounce") + [write_table(out, "bounce", rows)]
    return files, format_bounce_table(study).splitlines()


STUDIES = {"order": order, "stability": stability, "provot": provot, "discretization": discretization,
           "bounce": bounce}
"""Study name -> writer ``(out) -> (files, summary lines)``."""


def write_study(name, out="out/studies", log=print):
    """Run study `name` (or ``"all"``), write its figure and tables into `out`, print a summary.

    Parameters
    ----------
    name : str
        A key of :data:`STUDIES` (``"order"``, ``"stability"``, ``"provot"``,
        ``"discretization"``, ``"bounce"``) or ``"all"``.
    out : str or pathlib.Path
        Output directory, created if needed.
    log : callable
        Receives each line of the summary (a header per study with its run
        time in seconds and its files, then its key numbers).

    Returns
    -------
    list of pathlib.Path
        The files written: ``NAME.png`` and ``NAME.svg`` (the figure) and one or
        more CSV tables per study.
    """
    if not callable(log):
        raise ValueError(f"log must be callable (e.g. print), got {log!r}")
    if not isinstance(name, str):
        raise ValueError(f"name must be a study's name (a str), got {name!r}")
    names = list(STUDIES) if name == "all" else [name]
    for n in names:
        if n not in STUDIES:
            raise ValueError(f"unknown study {n!r}; expected one of {', '.join(map(repr, STUDIES))} or 'all'")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for n in names:
        start = time.perf_counter()
        files, lines = STUDIES[n](out)
        written += files
        log(f"study {n} ({time.perf_counter() - start:.1f} s): " + ", ".join(p.name for p in files))
        for line in lines:
            log(f"   {line}")
    return written
