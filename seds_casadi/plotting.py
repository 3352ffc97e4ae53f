"""Figures: streamlines of a learned DS with demonstrations and reproductions.

Matplotlib is imported lazily with the non-interactive Agg backend when no display is set, so
figures can be written on headless machines and in CI.
"""

from __future__ import annotations

import os

import numpy as np

__all__ = ["plot_streamlines", "save_figure"]


def _plt():
    import matplotlib

    if not os.environ.get("DISPLAY") and not os.environ.get("MPLBACKEND"):
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_streamlines(ds, demos=None, reproductions=None, ax=None, title=None,
                     normalised: bool = False, margin: float = 0.15, density: float = 1.2):
    """Streamlines of a 2-D DS (or the x-y plane through the target of a higher-dimensional one).

    Parameters
    ----------
    ds : StableDS or any object with ``predict(X)`` and ``target``
    demos : Demonstrations, optional
        Drawn as dots.
    reproductions : list of array (T, d), optional
        Drawn as lines.
    ax : matplotlib Axes, optional
    title : str, optional
    normalised : bool
        Colour by the target field h = f/||f|| (Eq. 8) instead of the speed of f.

    Returns
    -------
    matplotlib Axes
    """
    plt = _plt()
    if ax is None:
        _, ax = plt.subplots(figsize=(5, 4.5))
    d = len(ds.target)
    pts = [ds.target[None, :2]]
    if demos is not None:
        pts += [p[:, :2] for p in demos.positions]
    if reproductions is not None:
        pts += [np.asarray(r)[:, :2] for r in reproductions]
    P = np.concatenate(pts)
    lo, hi = P.min(axis=0), P.max(axis=0)
    span = np.maximum(hi - lo, 1e-9)
    lo, hi = lo - margin * span, hi + margin * span
    gx, gy = np.meshgrid(np.linspace(lo[0], hi[0], 60), np.linspace(lo[1], hi[1], 60))
    grid = np.tile(ds.target, (gx.size, 1))
    grid[:, 0], grid[:, 1] = gx.ravel(), gy.ravel()
    F = ds.predict(grid)[:, :2]
    speed = np.linalg.norm(F, axis=1)
    if normalised:
        F = F / np.maximum(speed, 1e-300)[:, None]
    ax.streamplot(gx, gy, F[:, 0].reshape(gx.shape), F[:, 1].reshape(gx.shape),
                  color=np.log10(np.maximum(speed, 1e-12)).reshape(gx.shape), cmap="Greys_r",
                  density=density, linewidth=0.7, arrowsize=0.8)
    if demos is not None:
        for p in demos.positions:
            ax.plot(p[:, 0], p[:, 1], ".", color="tab:red", ms=2.5, alpha=0.7)
    if reproductions is not None:
        for r in reproductions:
            r = np.asarray(r)
            ax.plot(r[:, 0], r[:, 1], "-", color="tab:blue", lw=1.5)
    ax.plot(*ds.target[:2], "k*", ms=12)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("x1" if d == 2 else "x")
    ax.set_ylabel("x2" if d == 2 else "y")
    if title:
        ax.set_title(title, fontsize=9)
    return ax


def save_figure(fig, path: str | os.PathLike, dpi: int = 110) -> None:
    """Save a figure atomically (written to a temporary name, then renamed) and close it."""
    plt = _plt()
    path = os.fspath(path)
    root, ext = os.path.splitext(path)
    tmp = f"{root}.tmp-{os.getpid()}{ext}"
    try:
        fig.savefig(tmp, dpi=dpi, bbox_inches="tight")
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
        plt.close(fig)
