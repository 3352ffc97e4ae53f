"""Figures of a learned dynamical system: streamlines of a DS (2-D, or planes through the
target of a higher-dimensional one) and the figure of ``seds-casadi fit``."""

from __future__ import annotations

import numpy as np

from .plotting import pyplot

__all__ = ["plot_streamlines", "plot_fit_views"]


def plot_streamlines(ds, demos=None, reproductions=None, ax=None, title=None,
                     normalised: bool = False, margin: float = 0.15, density: float = 1.2,
                     dims: tuple[int, int] = (0, 1), unit: str | None = None,
                     legend: bool = True):
    """Streamlines of a 2-D DS, or of a higher-dimensional one in the plane of two coordinates
    ``dims`` through the target (the other coordinates held at the target's).

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
    dims : (int, int)
        The coordinates shown (0-based, ``x0, x1, ...`` as in a demonstrations file).
    unit : str, optional
        The positions' unit for the axis labels (default: "the data's units").
    legend : bool
        A key of the demonstrations, reproductions and target.

    Returns
    -------
    matplotlib Axes
    """
    plt = pyplot()
    if ax is None:
        _, ax = plt.subplots(figsize=(5, 4.5))
    d = len(ds.target)
    i, j = (int(k) for k in dims)
    if not (0 <= i < d and 0 <= j < d and i != j):
        raise ValueError(f"dims must be two different coordinates below {d}, got {dims!r}")
    pts = [ds.target[None, [i, j]]]
    if demos is not None:
        pts += [p[:, [i, j]] for p in demos.positions]
    if reproductions is not None:
        pts += [np.asarray(r)[:, [i, j]] for r in reproductions]
    P = np.concatenate(pts)
    lo, hi = P.min(axis=0), P.max(axis=0)
    span = np.maximum(hi - lo, 1e-9)
    lo, hi = lo - margin * span, hi + margin * span
    gx, gy = np.meshgrid(np.linspace(lo[0], hi[0], 60), np.linspace(lo[1], hi[1], 60))
    grid = np.tile(ds.target, (gx.size, 1))
    grid[:, i], grid[:, j] = gx.ravel(), gy.ravel()
    F = ds.predict(grid)[:, [i, j]]
    speed = np.linalg.norm(F, axis=1)
    if normalised:
        F = F / np.maximum(speed, 1e-300)[:, None]
    ax.streamplot(gx, gy, F[:, 0].reshape(gx.shape), F[:, 1].reshape(gx.shape),
                  color=np.log10(np.maximum(speed, 1e-12)).reshape(gx.shape), cmap="Greys_r",
                  density=density, linewidth=0.7, arrowsize=0.8)
    key = [plt.Line2D([], [], color="0.3", lw=0.7, label="f(x) (darker: slower)")]
    if demos is not None:
        for p in demos.positions:
            ax.plot(p[:, i], p[:, j], ".", color="tab:red", ms=2.5, alpha=0.7)
        key.append(plt.Line2D([], [], ls="", marker=".", color="tab:red",
                              label="demonstrations"))
    if reproductions is not None:
        for r in reproductions:
            r = np.asarray(r)
            ax.plot(r[:, i], r[:, j], "-", color="tab:blue", lw=1.5)
        key.append(plt.Line2D([], [], color="tab:blue", label="reproductions"))
    key += ax.plot(ds.target[i], ds.target[j], "k*", ms=12, ls="", label="target")
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal", adjustable="box")
    u = f" [{unit}]" if unit else " (the data's units)"
    ax.set_xlabel(f"x{i}{u}")   # named as the columns of a demonstrations file
    ax.set_ylabel(f"x{j}{u}")
    if legend:
        ax.legend(handles=key, fontsize=7, loc="best", framealpha=0.85)
    if title:
        ax.set_title(title, fontsize=9)
    return ax


def plot_fit_views(ds, demos, reproductions=None, title: str = ""):
    """The figure of ``seds-casadi fit``: streamlines in the x0-x1 plane for 2-D data; for
    3-D or more, the x0-x1 and x0-x2 planes through the target and a 3-D view of the
    demonstrations and reproductions (the first three coordinates).

    Returns
    -------
    matplotlib Figure
    """
    plt = pyplot()
    d = len(ds.target)
    if d == 2:
        fig, ax = plt.subplots(figsize=(5.5, 5))
        plot_streamlines(ds, demos, reproductions, ax=ax, title=title)
        return fig
    fig = plt.figure(figsize=(15, 4.8))
    for k, dims in enumerate(((0, 1), (0, 2))):
        plot_streamlines(ds, demos, reproductions, ax=fig.add_subplot(1, 3, k + 1), dims=dims,
                         title=f"the x{dims[0]}-x{dims[1]} plane through the target",
                         legend=k == 0)
    ax = fig.add_subplot(1, 3, 3, projection="3d")
    for p in demos.positions:
        ax.plot(p[:, 0], p[:, 1], p[:, 2], ".", color="tab:red", ms=2, alpha=0.6)
    for r in [] if reproductions is None else reproductions:
        r = np.asarray(r)
        ax.plot(r[:, 0], r[:, 1], r[:, 2], "-", color="tab:blue", lw=1.2)
    ax.plot(*ds.target[:3], "k*", ms=12)
    ax.set(xlabel="x0", ylabel="x1", zlabel="x2")
    ax.set_title("3-D view: demonstrations (red), reproductions (blue), target (star)",
                 fontsize=9)
    fig.suptitle(title + (f" (first 3 of {d} coordinates)" if d > 3 else ""), fontsize=10)
    fig.tight_layout()
    return fig
