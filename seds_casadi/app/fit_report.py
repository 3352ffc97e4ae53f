"""The figure of a fit report (:class:`~seds_casadi.core.report.FitReport`): reproductions
against demonstrations, and their speeds over time."""

from __future__ import annotations

import numpy as np

from .plotting import pyplot

__all__ = ["plot_fit_report"]


def plot_fit_report(report, demos, title: str | None = None):
    """Two panels: the paths (the first two dimensions; position over time in 1-D) of each
    demonstration (grey) and its reproduction from the same start (colour, dashed when it
    does not reach the target), and the speeds over time, demonstration against reproduction.

    Parameters
    ----------
    report : FitReport
    demos : Demonstrations
        The demonstrations of the report.
    title : str, optional

    Returns
    -------
    matplotlib Figure
    """
    plt = pyplot()
    fig, (ax_p, ax_v) = plt.subplots(1, 2, figsize=(10, 4.3))
    dt = report.dt
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    pos = [np.asarray(p) + demos.target for p in demos.shifted_positions]
    for n, (p, v, path, sp, row) in enumerate(zip(pos, demos.velocities, report.paths,
                                                  report.speeds, report.rows, strict=True)):
        c = colours[n % len(colours)]
        ls = "-" if row.reached else "--"
        if demos.n_dims >= 2:
            ax_p.plot(p[:, 0], p[:, 1], color="0.6", lw=2.5, zorder=1)
            ax_p.plot(path[:, 0], path[:, 1], ls, color=c, lw=1.2, zorder=2,
                      label=f"demo {row.demo}")
            ax_p.plot(*p[0, :2], "o", color=c, ms=4)
        else:
            ax_p.plot(np.arange(len(p)) * dt, p[:, 0], color="0.6", lw=2.5)
            ax_p.plot(np.arange(len(path)) * dt, path[:, 0], ls, color=c, lw=1.2,
                      label=f"demo {row.demo}")
        ax_v.plot(np.arange(len(v)) * dt, np.linalg.norm(v, axis=1), color="0.6", lw=2.5)
        ax_v.plot(np.arange(len(sp)) * (report.speed_dt or dt), sp, ls, color=c, lw=1.2,
                  label=f"{row.demo}: peak x{row.speed_ratio:.2f}")
    if demos.n_dims >= 2:
        ax_p.plot(*demos.target[:2], "k*", ms=10)
        ax_p.set_xlabel("x1")
        ax_p.set_ylabel("x2")
        ax_p.set_aspect("equal", adjustable="datalim")
        ax_p.set_title("paths (grey: demonstrations)" + (" - first 2 of "
                                                          f"{demos.n_dims} dims"
                                                          if demos.n_dims > 2 else ""),
                       fontsize=9)
    else:
        ax_p.set_xlabel("t [s]")
        ax_p.set_title("position (grey: demonstrations)", fontsize=9)
    ax_v.set_xlabel("t [s]")
    ax_v.set_ylabel("speed")
    ax_v.set_title("speed (grey: demonstrations)", fontsize=9)
    ax_v.legend(fontsize=7)
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return fig
