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
    fig, axs = plt.subplots(len(learners), 1, figsize=(9.5, 3.6 * len(learners)), squeeze=False)
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
    save_figure(fig, os.path.join(out, "shots.png"))


def _motion_figure(motion, out) -> None:
    """The learned motion (Eq. 14): swings from a few starts turned by three angles, from above
    (x-y) and from the side (x-z), positions relative to the ball."""
    from ..motion.rotation import rotation_z

    plt = pyplot()
    fig, (top, side) = plt.subplots(2, 1, figsize=(8, 7.6), sharex=True,
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
    top.set_aspect("equal")
    side.set_xlabel("x, relative to the ball, along the unturned hit [m]")
    top.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    fig.suptitle(f"the learned hitting motion (Eq. 14), turned by alpha; v* = "
                 f"{motion.hitting_speed:.2f} m/s at kappa = 1", fontsize=10)
    fig.tight_layout()
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
