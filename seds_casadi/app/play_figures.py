"""The figures of ``seds-casadi play``: ``shots.png``, ``motion.png`` and
``hitting_parameters.png`` (each titled with the field, robot and learner it shows)."""

from __future__ import annotations

import os

import numpy as np

from .plotting import plot_field, pyplot, save_figure


def play_figures(fld, motion, data, fitted: dict, rows: list[dict], learners, out: str,
                 robot: str) -> None:
    """Write the three figures of a round into ``out``.

    Parameters
    ----------
    fld : Field
    motion : HittingMotion
    data : HittingDataset
        The teacher's data set (the learners' training data).
    fitted : dict
        Learner name -> fitted hitting-parameter model (or StrategyChoice).
    rows : list of dict
        The rows of ``shots.csv`` (with the ball ``path`` of each hit).
    """
    _shots_figure(fld, rows, learners, out, robot)
    _motion_figure(motion, out)
    _parameters_figure(fld, data, fitted, out)


def _shots_figure(fld, rows, learners, out, robot) -> None:
    plt = pyplot()
    b = fld.bounds
    # each panel as tall as the field drawn at the figure's width (a long field leaves no
    # empty band between the panels), plus its title and labels
    panel = float(np.clip(7.6 * (b[3] - b[2]) / (b[1] - b[0]), 1.0, 9.0)) + 1.2
    fig, axs = plt.subplots(len(learners), 1, figsize=(9.5, panel * len(learners)),
                            squeeze=False)
    for ax, m in zip(axs[:, 0], learners):
        rs = [r for r in rows if r["method"] == m]
        checked = [((r["ball_x_m"], r["ball_y_m"]), r["sunk_exudyn"] == r["sunk"])
                   for r in rs if r["sunk_exudyn"] != ""]
        plot_field(fld, ax=ax, paths=[r["path"] for r in rs if "path" in r],
                   sunk=[r["sunk"] for r in rs if "path" in r],
                   ball=np.array([[r["ball_x_m"], r["ball_y_m"]] for r in rs]),
                   hole=np.array([[r["hole_x_m"], r["hole_y_m"]] for r in rs]), checked=checked,
                   no_hit=np.array([[r["ball_x_m"], r["ball_y_m"]] for r in rs if not r["hit"]]))
        ax.set_title(f"{fld.name}, the {robot}, hitting parameters by {m}: "
                     f"{np.mean([r['sunk'] for r in rs]):.0%} of {len(rs)} shots sunk",
                     fontsize=9)
    fig.tight_layout()
    # the field is drawn at equal scales: fit the panels' height to the width they got
    width = axs[0, 0].get_window_extent().width / fig.dpi
    fig.set_size_inches(9.5, len(learners) * (width * (b[3] - b[2]) / (b[1] - b[0]) + 1.1))
    fig.tight_layout()
    save_figure(fig, os.path.join(out, "shots.png"))


def _motion_figure(motion, out) -> None:
    """The learned motion (Eq. 14): swings from a few starts turned by three angles, from above
    (x-y) and from the side (x-z), positions relative to the ball."""
    from ..motion.rotation import rotation_z

    plt = pyplot()
    fig, (top, side) = plt.subplots(2, 1, figsize=(8, 7.8),
                                    gridspec_kw={"height_ratios": [3, 1.3]})
    for deg, c in ((0.0, "k"), (15.0, "tab:blue"), (-15.0, "tab:orange")):
        alpha = np.radians(deg)
        for i, y in enumerate((-0.1, 0.0, 0.1)):
            r = motion.rollout(rotation_z(alpha) @ np.array([-0.3, y, 0.05]), alpha=alpha,
                               rest_time=0.1, dt=0.004)
            lab = f"alpha = {deg:+.0f} deg" if i == 0 else None
            top.plot(r.positions[:, 0], r.positions[:, 1], "-", color=c, lw=1, label=lab)
            side.plot(r.positions[:, 0], r.positions[:, 2], "-", color=c, lw=1, label=lab)
            top.plot(*r.positions[0, :2], "o", color=c, ms=3)
            side.plot(r.positions[0, 0], r.positions[0, 2], "o", color=c, ms=3)
    for ax, (lab, name) in zip((top, side), (("y", "from above (x-y)"),
                                             ("z", "from the side (x-z)"))):
        ax.plot(0, 0, "o", color="w", mec="k", ms=9, label="ball (contact point)")
        ax.set_ylabel(f"{lab}, relative to the ball [m]")
        ax.grid(alpha=0.3)
        ax.set_title(f"club-head paths {name}; dots: starts", fontsize=9)
    # the same x range in both panels, each with its ticks and label; the view from above at
    # equal scales: its y range (or, if the paths need more, both x ranges) sized to its box
    for ax in (top, side):
        ax.set_xlabel("x, relative to the ball, along the unturned hit [m]")
    lo = min(top.get_xlim()[0], side.get_xlim()[0])
    hi = max(top.get_xlim()[1], side.get_xlim()[1])
    ylo, yhi = top.get_ylim()
    top.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    fig.suptitle(f"the learned hitting motion (Eq. 14), turned by alpha; v* = "
                 f"{motion.hitting_speed:.2f} m/s at kappa = 1", fontsize=10)
    fig.tight_layout()
    box = top.get_window_extent()
    ratio = box.height / box.width
    if (yhi - ylo) > (hi - lo) * ratio:
        grow = ((yhi - ylo) / ratio - (hi - lo)) / 2
        lo, hi = lo - grow, hi + grow
    mid, half = (ylo + yhi) / 2, (hi - lo) * ratio / 2
    top.set_ylim(mid - half, mid + half)
    for ax in (top, side):
        ax.set_xlim(lo, hi)
    save_figure(fig, os.path.join(out, "motion.png"))


def _parameters_figure(fld, data, fitted, out) -> None:
    """Each learner's hitting angle (and gain) against the teacher's, on the teacher's data."""
    from ..minigolf.strategy_choice import StrategyChoice

    plt = pyplot()
    Y = data.outputs
    names = ("hitting angle alpha [deg]", "gain kappa (of v*)")[:Y.shape[1]]
    fig, axs = plt.subplots(1, len(names), figsize=(5.2 * len(names), 4.6), squeeze=False)
    for m, model in fitted.items():
        if isinstance(model, StrategyChoice):
            pred = np.empty_like(Y, dtype=float)
            for k in np.unique(data.labels):
                sel = data.labels == k
                pred[sel] = model.predict_strategy(data.situations[sel], int(k))
        else:
            pred = np.asarray(model.predict(data.situations), float)
        for j, ax in enumerate(axs[0]):
            if j < pred.shape[1]:
                ax.plot(Y[:, j], pred[:, j], "o", ms=4, alpha=0.7, label=m)
    for j, (ax, name) in enumerate(zip(axs[0], names)):
        lo, hi = Y[:, j].min(), Y[:, j].max()
        ax.plot([lo, hi], [lo, hi], "k-", lw=0.8, label="model = teacher")
        ax.set_xlabel(f"teacher's {name}")
        ax.set_ylabel(f"model's {name}")
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
    fig.suptitle(f"{fld.name}: the hitting-parameter models on the teacher's {len(Y)} good "
                 f"shots (training data)", fontsize=10)
    fig.tight_layout()
    save_figure(fig, os.path.join(out, "hitting_parameters.png"))


def strategy_figure(fld, strategies, rows, learner: str, out: str) -> None:
    """``strategies.png``: Fig. 4a of the first situation played, its success regions coloured
    by strategy, and each strategy's shot from there; the one ``learner`` chose marked."""
    from .plotting import plot_strategies

    first = next(r for r in rows if r["method"] == learner)
    ball = np.array([first["ball_x_m"], first["ball_y_m"]])
    hole = np.array([first["hole_x_m"], first["hole_y_m"]])
    fig, (a1, a2) = pyplot().subplots(1, 2, figsize=(13, 4.6),
                                     gridspec_kw={"width_ratios": [1, 1.4]})
    plot_strategies(fld, strategies.stroke, strategies, ball, hole, a1, a2,
                    chosen=first["strategy"])
    a2.set_title(f"{fld.name}: each strategy's centre shot from this ball; {learner} chose "
                 f"strategy "
                 f"{first['strategy']} (thick)", fontsize=9)
    save_figure(fig, os.path.join(out, "strategies.png"))


def adaptation_figure(fld, adaptations: dict, tests: list[dict], out: str) -> None:
    """``adaptation.png``: the round's success against the adaptation shots learned from
    (``tests``: the round's rows, ``adapt_shots`` each) with each adaptation shot's distance
    from the hole, the green's parameters as the robot estimated them shot after shot, and the
    learned correction of the first learner over the situations
    (:mod:`seds_casadi.game.adapt`)."""
    plt = pyplot()
    fig, axs = plt.subplots(1, 3, figsize=(15.5, 4.6))
    ax = axs[0]
    ax_d = ax.twinx()
    for j, (m, a) in enumerate(adaptations.items()):
        colour = f"C{j}"
        ks = sorted({r["adapt_shots"] for r in tests if r["method"] == m})
        rate = [100 * np.mean([r["sunk"] for r in tests
                               if r["method"] == m and r["adapt_shots"] == k]) for k in ks]
        ax.plot(ks, rate, "o-", color=colour, lw=2, label=f"{m}: round sunk [%]")
        n = np.arange(1, len(a.steps) + 1)
        ax_d.plot(n, a.miss_distance, ".:", color=colour, ms=5, lw=0.8,
                  label=f"{m}: adaptation shot's miss [m]")
    ax.set_ylim(-3, 103)
    ax.set_xlabel("adaptation shots learned from")
    ax.set_ylabel("round sunk [%]")
    ax_d.set_ylabel("adaptation shot: distance from the hole [m] (0: sunk)")
    h1, l1 = ax.get_legend_handles_labels()
    h2, l2 = ax_d.get_legend_handles_labels()
    ax.legend(h1 + h2, l1 + l2, fontsize=8, loc="center right")
    ax.set_title("success and misses against the adaptation shots", fontsize=10)
    ax.grid(alpha=0.3)
    ax = axs[1]
    first = next(iter(adaptations.values()))
    Q = np.array([s.green for s in first.steps]).reshape(-1, 5)
    n = np.arange(1, len(Q) + 1)
    ax.plot(n, np.exp(Q[:, 0]), "o-", ms=3, label="rolling resistance (x nominal)")
    ax.plot(n, np.exp(Q[:, 3]), "s-", ms=3, label="launch speed (x measured)")
    ax.set_ylabel("factor")
    ax2 = ax.twinx()
    ax2.plot(n, 100 * Q[:, 1], "--", color="C2", label="tilt x [%]")
    ax2.plot(n, 100 * Q[:, 2], "--", color="C3", label="tilt y [%]")
    ax2.set_ylabel("tilt [%]")
    h1, l1 = ax.get_legend_handles_labels()
    h2, l2 = ax2.get_legend_handles_labels()
    ax.legend(h1 + h2, l1 + l2, fontsize=8, loc="best")
    ax.set_xlabel(f"adaptation shot ({next(iter(adaptations))})")
    ax.set_title("the green as the robot estimated it", fontsize=10)
    ax.grid(alpha=0.3)
    ax = axs[2]
    model = first.model
    balls, holes = fld.situations.sample(400, np.random.default_rng(0))
    S = holes - balls
    C = model.correction(S)
    spread = np.ptp(S, axis=0)
    if np.count_nonzero(spread > 1e-9) >= 2:
        x = balls[:, 0] if np.ptp(balls[:, 0]) > 1e-9 else holes[:, 0]
        y = balls[:, 1] if np.ptp(balls[:, 1]) > 1e-9 else holes[:, 1]
        sc = ax.scatter(x, y, c=100 * (np.exp(C[:, 1]) - 1), cmap="coolwarm", s=14)
        fig.colorbar(sc, ax=ax, label="kappa correction [%]")
        if np.ptp(C[:, 0]) > 1e-6:   # the angle's correction as labelled contour lines
            cs = ax.tricontour(x, y, C[:, 0], levels=6, colors="k", linewidths=0.7)
            ax.clabel(cs, fmt="%.1f deg", fontsize=7)
        ax.set_xlabel("ball x [m]")
        ax.set_ylabel("ball y [m]")
        ax.set_aspect("equal", adjustable="datalim")
        for st in first.steps:
            ax.plot(*st.result.shot.ball, "k+", ms=6)
    else:
        j = int(np.argmax(spread))
        place = holes if np.ptp(holes[:, j]) > 1e-9 else balls
        order = np.argsort(place[:, j])
        ax.plot(place[order, j], C[order, 0], "C0-", label="alpha correction [deg]")
        ax.set_ylabel("alpha correction [deg]")
        ax2 = ax.twinx()
        ax2.plot(place[order, j], 100 * (np.exp(C[order, 1]) - 1), "C1--",
                 label="kappa correction [%]")
        ax2.set_ylabel("kappa correction [%]")
        ax.set_xlabel(f"{'hole' if place is holes else 'ball'} {'xy'[j]} [m]")
        h1, l1 = ax.get_legend_handles_labels()
        h2, l2 = ax2.get_legend_handles_labels()
        ax.legend(h1 + h2, l1 + l2, fontsize=8)
    ax.set_title(f"the learned correction ({next(iter(adaptations))}; +: shots played)",
                 fontsize=10)
    ax.grid(alpha=0.3)
    fig.suptitle(f"self-correction on {first.world.label} (taught on {fld.name})", fontsize=11)
    fig.tight_layout()
    save_figure(fig, os.path.join(out, "adaptation.png"))
