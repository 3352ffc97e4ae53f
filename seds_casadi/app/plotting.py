"""Figures: success maps (Fig. 4a), hitting-parameter models (Fig. 10 and 11), fields with ball
paths, the arm's frames and the strategies; the streamlines of a learned DS are in
:mod:`seds_casadi.app.plot_ds`.

Matplotlib is imported lazily (:func:`pyplot`) with the non-interactive Agg backend when no
display is set, so figures can be written on headless machines and in CI.
"""

from __future__ import annotations

import os

import numpy as np

from ..core._signals import raise_pending_interrupt

__all__ = ["pyplot", "save_figure", "plot_success_map", "plot_regression_1d", "plot_joint_gmm",
           "plot_field", "plot_arm_frames", "plot_strategies", "STRATEGY_COLOURS"]

#: colours of strategies 0, 1, 2, ... in the strategy figures
STRATEGY_COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2",
                    "#17becf", "#bcbd22")


def pyplot():
    """``matplotlib.pyplot``, with the non-interactive Agg backend when no display is set."""
    import matplotlib

    if not os.environ.get("DISPLAY") and not os.environ.get("MPLBACKEND"):
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig, path: str | os.PathLike, dpi: int = 110) -> None:
    """Save a figure atomically (written to a temporary name, then renamed) and close it.

    The temporary name is ``.tmp-PID-NAME`` beside ``path`` (hidden, and the kind of name
    :func:`seds_casadi.app.outdir.sweep_temporary_files` removes when a run was killed while
    saving; the extension stays last, so the format is still chosen from it)."""
    plt = pyplot()
    path = os.fspath(path)
    folder, name = os.path.split(path)
    tmp = os.path.join(folder, f".tmp-{os.getpid()}-{name}")
    try:
        fig.savefig(tmp, dpi=dpi, bbox_inches="tight")
        raise_pending_interrupt()  # a signal's interrupt first: nothing written after it
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
        plt.close(fig)



def plot_success_map(success: np.ndarray, alphas, kappas, ax=None, title=None, chosen=None):
    """Fig. 4a: success (green) or failure (red) over the (alpha, kappa) grid.

    Parameters
    ----------
    success : array of bool, shape (n_kappa, n_alpha)
    alphas : array, shape (n_alpha,)
        Hitting angles [rad].
    kappas : array, shape (n_kappa,)
    chosen : (alpha, kappa), optional
        The teacher's choice, marked with a cross.
    """
    plt = pyplot()
    from matplotlib.colors import ListedColormap

    if ax is None:
        _, ax = plt.subplots(figsize=(5, 4))
    a = np.rad2deg(np.asarray(alphas))
    ax.pcolormesh(a, kappas, np.asarray(success, float), shading="nearest",
                  cmap=ListedColormap(["#d9534f", "#5cb85c"]), vmin=0, vmax=1)
    key = [plt.Line2D([], [], ls="", marker="s", ms=9, color="#5cb85c", label="sinks the ball"),
           plt.Line2D([], [], ls="", marker="s", ms=9, color="#d9534f", label="misses")]
    if chosen is not None:
        key += ax.plot(np.rad2deg(chosen[0]), chosen[1], "kx", ms=10, mew=2,
                       label="the teacher's choice")
    ax.legend(handles=key, loc="upper right", fontsize=8, framealpha=0.9)
    ax.set_xlabel("hitting angle alpha [deg]")
    ax.set_ylabel("speed gain kappa (of v*)")
    if title:
        ax.set_title(title, fontsize=9)
    return ax


def plot_strategies(field, stroke, strategies, ball, hole, ax_map=None, ax_field=None,
                    resolution=None, chosen=None):
    """Fig. 4a with the strategies coloured: the success map of one situation over (alpha,
    kappa) with bank shots, each successful region coloured by the strategy it belongs to
    (grey: a region of none of the kept strategies; red: no success), the regions' centre shots
    numbered; and the ball paths of those shots on the field.

    Parameters
    ----------
    field : Field
    stroke : Stroke
    strategies : StrategySet
    ball, hole : array, shape (2,)
    resolution : (int, int), optional
        Grid of the map (default: the exploration's).
    chosen : int, optional
        A strategy's label to mark as the one played (thick path, starred shot).

    Returns
    -------
    (ax_map, ax_field)
    """
    from matplotlib.colors import ListedColormap

    from ..minigolf.ball import simulate_shots
    from ..minigolf.strategies import explore_situation

    plt = pyplot()
    if ax_map is None or ax_field is None:
        _, (ax_map, ax_field) = plt.subplots(1, 2, figsize=(13, 4.2),
                                             gridspec_kw={"width_ratios": [1, 1.4]})
    st = strategies.settings
    res = resolution or st.get("resolution", (301, 73))
    alphas = np.deg2rad(np.linspace(*st.get("alpha_range", (-75, 75)), int(res[0])))
    kappas = np.linspace(*st.get("kappa_range", (0.6, 2.4)), int(res[1]))
    regions = explore_situation(field, stroke, ball, hole, alphas, kappas,
                                st.get("tolerance", (1.0, 0.03)), st.get("min_cells", 4),
                                keep_masks=True)
    labels = strategies.label_regions(ball, hole, regions)
    n = len(strategies.strategies)
    img = np.zeros((len(kappas), len(alphas)), int)  # 0 failure, 1 other region, 2 + label
    for r, lab in zip(regions, labels):
        img[r.mask] = 1 if lab is None else 2 + lab
    colours = ["#f2b8b5", "0.6"] + [STRATEGY_COLOURS[k % len(STRATEGY_COLOURS)]
                                    for k in range(n)]
    ax_map.pcolormesh(np.rad2deg(alphas), kappas, img, shading="nearest",
                      cmap=ListedColormap(colours), vmin=-0.5, vmax=len(colours) - 0.5)
    shots = []
    for r, lab in zip(regions, labels):
        if lab is None:
            continue
        c = STRATEGY_COLOURS[lab % len(STRATEGY_COLOURS)]
        ax_map.plot(np.rad2deg(r.alpha), r.kappa, "*" if lab == chosen else "o", color="k",
                    mfc=c, ms=12 if lab == chosen else 7)
        ax_map.annotate(str(lab), (np.rad2deg(r.alpha), r.kappa), textcoords="offset points",
                        xytext=(6, 4), fontsize=8)
        shots.append((lab, r))
    handles = [plt.Line2D([], [], ls="", marker="s", ms=9, color=STRATEGY_COLOURS[
        s.label % len(STRATEGY_COLOURS)], label=s.describe()) for s in strategies.strategies]
    handles.append(plt.Line2D([], [], ls="", marker="s", ms=9, color="0.6",
                              label="other successful regions"))
    ax_map.legend(handles=handles, fontsize=6.5, loc="upper center",
                  bbox_to_anchor=(0.5, -0.16), ncol=1)
    ax_map.set_xlabel("hitting angle alpha [deg]")
    ax_map.set_ylabel("speed gain kappa (of v*)")
    ax_map.set_title(f"Fig. 4a with strategies: ball {np.round(ball, 2).tolist()}, hole "
                     f"{np.round(hole, 2).tolist()}", fontsize=9)
    plot_field(field, ax=ax_field, ball=ball, hole=hole)
    if shots:
        A = np.array([r.alpha for _, r in shots])
        K = np.array([r.kappa for _, r in shots])
        res_paths = simulate_shots(field, np.tile(np.asarray(ball, float), (len(A), 1)),
                                   stroke.launch_velocity(A, K), hole=hole, engine="numpy",
                                   record_paths=True)
        for (lab, _), path in zip(shots, res_paths.paths):
            ax_field.plot(path[:, 0], path[:, 1], "-", lw=3 if lab == chosen else 1.5,
                          color=STRATEGY_COLOURS[lab % len(STRATEGY_COLOURS)])
    ax_field.set_title(f"{field.name}: each strategy's centre shot from this ball\n(colours as "
                       f"on the map; thick: the one played)", fontsize=9)
    return ax_map, ax_field


def plot_regression_1d(x, y, train, models: dict, ax_row=None, xlabel="s_y [m]",
                       ylabel="alpha [deg]", x_query=None, column: int = 1):
    """Fig. 10: each model's mean and 2-sigma band over one input, with the data set.

    Parameters
    ----------
    x : array, shape (n, d_in)
        Situations of the data set (the ``column`` varies).
    y : array, shape (n,)
        Output to show (first output of the models).
    train : array of int
        Indices used for training (black crosses; the others red).
    models : dict
        Title -> fitted model with ``predict(S, return_var=True)``.
    """
    plt = pyplot()
    if ax_row is None:
        _, ax_row = plt.subplots(1, len(models), figsize=(5 * len(models), 3.6), sharey=True)
    ax_row = np.atleast_1d(ax_row)
    x = np.atleast_2d(x)
    xs = x[:, column]
    if x_query is None:
        span = np.ptp(xs)
        x_query = np.linspace(xs.min() - 0.3 * span, xs.max() + 0.3 * span, 300)
    Q = np.tile(x[0], (len(x_query), 1))
    Q[:, column] = x_query
    test = np.setdiff1d(np.arange(len(xs)), train)
    for ax, (title, m) in zip(ax_row, models.items()):
        mean, var = m.predict(Q, return_var=True)
        sd = np.sqrt(np.maximum(var[:, 0], 0))
        ax.fill_between(x_query, mean[:, 0] - 2 * sd, mean[:, 0] + 2 * sd, color="0.8",
                        label="2 sigma")
        ax.plot(x_query, mean[:, 0], "b-", lw=1.5, label="mean")
        ax.plot(xs[test], y[test], "r+", ms=8, mew=1.5, label="test data")
        ax.plot(xs[train], y[train], "k+", ms=8, mew=1.5, label="training data")
        ax.set_title(title, fontsize=9)
        ax.set_xlabel(xlabel)
    ax_row[0].set_ylabel(ylabel)
    ax_row[0].legend(fontsize=7, loc="best")
    return ax_row


def plot_joint_gmm(model, outputs: np.ndarray, ax_row=None, names=("alpha [deg]", "kappa"),
                   label: str = "teacher's shots"):
    """Fig. 11: the joint GMM's two outputs with each Gaussian, and each Gaussian's absolute
    correlation matrix.

    Parameters
    ----------
    model : GMRModel
        Fitted with ``separate=False`` on 2-D situations and 2 outputs.
    outputs : array, shape (n, 2)
        The data set's outputs.
    label : str, default "teacher's shots"
        The outputs' legend entry.
    """
    plt = pyplot()
    (_, gm), = model.gmms_
    K = gm.n_components
    if ax_row is None:
        fig = plt.figure(figsize=(4 + 2.2 * K, 3.8))
        ax_row = [fig.add_subplot(1, K + 1, 1)] + [fig.add_subplot(1, K + 1, k + 2)
                                                  for k in range(K)]
    ax = ax_row[0]
    d = model.n_inputs_
    ax.plot(outputs[:, 0], outputs[:, 1], "k.", ms=4, label=label)
    t = np.linspace(0, 2 * np.pi, 100)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for k in range(K):
        mu = gm.means_[k, d:d + 2]
        C = gm.covariances_[k][d:d + 2, d:d + 2]
        w, V = np.linalg.eigh(C)
        ell = (V * 2 * np.sqrt(np.maximum(w, 0))) @ np.vstack([np.cos(t), np.sin(t)])
        ax.plot(mu[0] + ell[0], mu[1] + ell[1], color=colors[k % len(colors)], lw=1.5,
                label=f"Gaussian {k + 1} (2 sigma)")
        ax.plot(*mu, "o", color=colors[k % len(colors)])
    ax.set_xlabel(names[0])
    ax.set_ylabel(names[1])
    ax.legend(fontsize=7)
    ax.set_title("outputs and Gaussians", fontsize=9)
    labels = ["s_x", "s_y", names[0].split()[0], names[1].split()[0]][-gm.means_.shape[1]:]
    for k in range(K):
        C = gm.covariances_[k]
        s = np.sqrt(np.diag(C))
        R = np.abs(C / np.outer(s, s))
        a = ax_row[k + 1]
        a.imshow(R, vmin=0, vmax=1, cmap="Greys")
        for i in range(len(R)):
            for j in range(len(R)):
                a.text(j, i, f"{R[i, j]:.2f}", ha="center", va="center", fontsize=7,
                       color="w" if R[i, j] > 0.5 else "k")
        a.set_xticks(range(len(R)), labels, fontsize=8)
        a.set_yticks(range(len(R)), labels, fontsize=8)
        a.set_title(f"|corr|, Gaussian {k + 1}", fontsize=9, color=colors[k % len(colors)])
    return ax_row


def plot_field(field, ax=None, paths=None, sunk=None, ball=None, hole=None, n: int = 200,
               checked=None, legend: bool = True, no_hit=None):
    """The field's height map with ball paths (green: sunk, red: missed) and a key.

    Parameters
    ----------
    field : Field
    paths : list of array (T, 2), optional
    sunk : array of bool, optional
    ball, hole : array, shape (2,) or (n, 2), optional
    checked : list of (ball (2,), agreed: bool), optional
        Shots checked again in exudyn: a diamond at the ball, filled when exudyn agreed.
    legend : bool
        A key of the paths, balls, holes and checks drawn.
    no_hit : array, shape (m, 2), optional
        Balls the club never struck (the swing could not start or did not reach the ball): a
        red cross over the ball, so that a shot without a path is still seen.
    """
    from matplotlib.lines import Line2D

    plt = pyplot()
    if ax is None:
        _, ax = plt.subplots(figsize=(8, 3.4))
    b = field.bounds
    X, Y = np.meshgrid(np.linspace(b[0], b[1], n), np.linspace(b[2], b[3], max(20, n // 3)))
    Z = field.surface.height(np.column_stack([X.ravel(), Y.ravel()])).reshape(X.shape)
    if np.ptp(Z) > 1e-6:   # a height map; a flat field is one colour, said in the key
        im = ax.contourf(X, Y, Z * 100, levels=20, cmap="terrain")
        plt.colorbar(im, ax=ax, label="surface height [cm]", shrink=0.8)
        flat = []
    else:
        ax.set_facecolor("#b8dcb0")
        flat = [plt.Line2D([], [], ls="", marker="s", ms=9, color="#b8dcb0",
                           label=f"flat surface (z = {float(Z.mean()) * 100:.3g} cm)")]
    holes = np.atleast_2d(field.hole if hole is None else hole)
    for h in holes:
        ax.add_patch(plt.Circle(h, field.hole_radius, color="k", fill=False, lw=1.2))
    key = flat + [Line2D([], [], color="k", marker="o", mfc="none", ms=8, ls="",
                         label="hole")]
    for i, p in enumerate(paths or []):
        ok = bool(sunk[i]) if sunk is not None else True
        ax.plot(p[:, 0], p[:, 1], "-", color="g" if ok else "r", lw=0.9, alpha=0.8)
    if paths:
        found = {bool(sunk[i]) if sunk is not None else True for i in range(len(paths))}
        key += [Line2D([], [], color=c, label=lab) for ok, c, lab in
                ((True, "g", "ball path, sunk"), (False, "r", "ball path, missed")) if ok in found]
    if ball is not None:
        B = np.atleast_2d(ball)
        ax.plot(B[:, 0], B[:, 1], "wo", mec="k", ms=4)
        key.append(Line2D([], [], color="w", marker="o", mec="k", ms=4, ls="", label="ball"))
    if no_hit is not None and len(no_hit):
        N = np.atleast_2d(no_hit)
        ax.plot(N[:, 0], N[:, 1], "x", color="r", ms=9, mew=2)
        key.append(Line2D([], [], color="r", marker="x", ms=7, mew=2, ls="",
                          label="not hit (shots.csv: miss_reason)"))
    for xy, agreed in checked or []:
        ax.plot(*xy, "D", ms=9, mec="m", mfc="m" if agreed else "none", mew=1.5, alpha=0.8)
    if checked:
        key.append(Line2D([], [], color="m", marker="D", ms=7, ls="",
                          label="checked in exudyn (filled: agrees)"))
    ax.set_aspect("equal")
    ax.set_xlim(b[0], b[1])
    ax.set_ylim(b[2], b[3])
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(field.name, fontsize=9)
    if legend:
        ax.legend(handles=key, fontsize=7, loc="upper left", bbox_to_anchor=(1.18, 1.0),
                  frameon=False)
    return ax


def plot_arm_frames(robot, qs, ax=None, ball=None, colors=None, alpha_min: float = 0.25):
    """Fig. 6g: the arm as a chain of joint positions with its club, at several configurations,
    in a 3-D axis (later frames darker).

    Parameters
    ----------
    robot : Robot
    qs : array, shape (k, nv)
    ball : array, shape (3,), optional
    """
    import pinocchio as pin

    plt = pyplot()
    if ax is None:
        fig = plt.figure(figsize=(6, 5))
        ax = fig.add_subplot(projection="3d")
    M = robot.base_placement
    for i, q in enumerate(qs):
        pin.framesForwardKinematics(robot.model, robot.data, np.asarray(q, float))
        pts = [M.translation] + [(M * robot.data.oMi[j]).translation
                                 for j in range(1, robot.model.njoints)]
        head = (M * robot.data.oMf[robot.head_frame]).translation
        fl = robot.model.frames[robot.head_frame].parentFrame
        flange = (M * robot.data.oMf[fl]).translation
        P = np.array(pts + [flange])
        a = alpha_min + (1 - alpha_min) * i / max(1, len(qs) - 1)
        c = colors[i] if colors is not None else "k"
        last = i == len(qs) - 1
        ax.plot(P[:, 0], P[:, 1], P[:, 2], "-o", color=c, ms=2.5, lw=1.6, alpha=a,
                label=f"{robot.name} arm (dots: joints)" if last else None)
        ax.plot([flange[0], head[0]], [flange[1], head[1]], [flange[2], head[2]], "-",
                color="tab:brown", lw=2.2, alpha=a, label="club" if last else None)
    if ball is not None:
        ax.scatter(*np.asarray(ball, float), s=40, color="w", edgecolors="k", label="ball")
    ax.legend(fontsize=7, loc="upper left")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    return ax


def plot_1d_reproductions(ds, demos, reproductions, ax=None, title=None):
    """A 1-D DS (where :func:`~seds_casadi.app.plot_ds.plot_streamlines` has no plane to draw):
    position against time of the demonstrations (dots) and of the reproductions from their
    starts (lines)."""
    plt = pyplot()
    if ax is None:
        _, ax = plt.subplots(figsize=(5, 4.5))
    dt = demos.estimated_dt()
    for p in demos.positions:
        ax.plot(dt * np.arange(len(p)), p[:, 0], ".", color="tab:red", ms=2.5, alpha=0.7)
    for r in reproductions:
        r = np.asarray(r)
        ax.plot(dt * np.arange(len(r)), r[:, 0], color="tab:blue", lw=1.2)
    ax.axhline(float(ds.target[0]), color="k", lw=0.6, ls="--")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("x")
    ax.set_title(title or "1-D DS: demonstrations (dots), reproductions (lines)")
    return ax
