"""The robot's launch, measured for the teacher: the arm's own swings over an (alpha, kappa)
grid, each launched by :func:`~seds_casadi.game.shot.swing_launch` (the one definition of a
robot's launch), kept as a :class:`~seds_casadi.minigolf.stroke.LaunchTable`.

With it the teacher's ball-model search (:mod:`seds_casadi.minigolf.teacher`) sees the ball
leave the club as it leaves this arm's club: the arm's effective mass at the face (from 0.26 kg
to 0.98 kg across the shipped arms, against the ideal club's 0.35 kg), its speed error at fast
swings and the face's direction. An arm that hits the ball in none of the grid's swings is
refused before any teaching, with what it lacks.
"""

from __future__ import annotations

import numpy as np

from ..minigolf.stroke import LaunchTable
from ..minigolf.teacher import teacher_ranges
from .scene import Scene
from .shot import swing_launch


def calibrate_launch(scene: Scene, alpha_range=None, kappa_range=None, n_alpha: int = 7,
                     n_kappa: int = 7, ball=None) -> LaunchTable:
    """Measure the scene robot's launch over a grid of hitting parameters.

    A measurement, not a learner: a pure function of the scene that returns a value (the
    :class:`~seds_casadi.minigolf.stroke.LaunchTable`); nothing is fitted.

    Parameters
    ----------
    scene : Scene
    alpha_range : (float, float), optional
        Hitting angles [deg]; default the field's teacher's ``alpha_range``
        (:func:`~seds_casadi.minigolf.teacher.teacher_ranges`).
    kappa_range : (float, float), optional
        Speed gains; default the field's teacher's ``kappa_range``.
    n_alpha, n_kappa : int
        Grid points (at least 2 each): ``n_alpha * n_kappa`` swings, each simulated up to
        its hit (about 0.05 s).
    ball : array, shape (2,), optional
        Where the swings are played (default: the middle of the field's declared ball
        positions); the robot stands beside it as in the round.

    Returns
    -------
    LaunchTable
        speed factor |launch| / |commanded club velocity| and the launch's angle from it,
        per (kappa, alpha); 0 where the swing did not reach the ball.

    Raises
    ------
    ValueError
        When no swing of the grid hits the ball (the arm cannot play this field: it says what
        failed).
    """
    if int(n_alpha) < 2 or int(n_kappa) < 2:
        raise ValueError(f"n_alpha and n_kappa must be at least 2, got {n_alpha}, {n_kappa}")
    default_alpha, default_kappa = teacher_ranges(scene.field)
    alpha_range = default_alpha if alpha_range is None else alpha_range
    kappa_range = default_kappa if kappa_range is None else kappa_range
    lo, hi = (float(v) for v in alpha_range)
    klo, khi = (float(v) for v in kappa_range)
    if not (lo < hi and 0 < klo < khi):
        raise ValueError(f"alpha_range {alpha_range} and kappa_range {kappa_range} must be "
                         "increasing pairs, with positive gains")
    if ball is None:
        sit = scene.field.situations.ball
        designs = sit.design(9)
        ball = designs[len(designs) // 2]
    alphas = np.deg2rad(np.linspace(lo, hi, int(n_alpha)))
    kappas = np.linspace(klo, khi, int(n_kappa))
    stroke = scene.stroke.with_launch(None)
    factor = np.zeros((len(kappas), len(alphas)))
    offset = np.zeros_like(factor)
    failures: list[str] = []
    for i, k in enumerate(kappas):
        for j, a in enumerate(alphas):
            try:
                _, launch = swing_launch(scene, ball, float(a), float(k), {"rest_time": 0.0})
            except ValueError as exc:
                failures.append(str(exc))
                continue
            if launch is None:
                failures.append("the club did not reach the ball")
                continue
            c = stroke.club_velocity(a, k)[0, :2]
            factor[i, j] = np.linalg.norm(launch) / np.linalg.norm(c)
            offset[i, j] = np.arctan2(c[0] * launch[1] - c[1] * launch[0], c @ launch)
    if not np.any(factor > 0):
        why = max(set(failures), key=failures.count) if failures else "no swing"
        raise ValueError(
            f"the {scene.robot} hits the ball in none of {factor.size} swings over alpha "
            f"{lo:g}..{hi:g} deg and kappa {klo:g}..{khi:g} at ball "
            f"{np.round(np.asarray(ball, float), 3).tolist()} on {scene.field.name} "
            f"(most often: {why}); give it a base nearer the ball, demonstrations it can "
            f"follow at this scale, or another robot")
    return LaunchTable(alphas, kappas, factor, offset, str(scene.robot))
