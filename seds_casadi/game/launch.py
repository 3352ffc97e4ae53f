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

#: the largest error of the bilinear table at a cell's centre (relative, in the speed factor,
#: or in the angle [rad]) before the cell is split (:func:`calibrate_launch`)
REFINE_TOLERANCE = 0.005


def calibrate_launch(scene: Scene, alpha_range=None, kappa_range=None, n_alpha: int = 7,
                     n_kappa: int = 7, ball=None, refine: int = 1,
                     check=None) -> LaunchTable:
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
    refine : int
        Rounds of refinement: the swing at the centre of every grid cell is measured, and
        where the table's bilinear interpolation misses it by more than
        :data:`REFINE_TOLERANCE`, the cell's middle lines (an angle and a gain) are added to
        the grid. An arm whose speed saturates in the grid (its launch's knee, e.g. the xArm7
        at kappa 1.2-1.5) otherwise gets a table 2-4 % off near the knee, and the teacher's
        shots there miss; a smooth launch costs only the centres' swings.
    check : callable, optional
        Called with the first grid's table before any refinement (e.g. the teacher's launch
        speed check): an arm it refuses is refused without the refinement's swings.

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
    failures: list[str] = []
    seen: dict[tuple[float, float], tuple[float, float]] = {}

    def measure(a: float, k: float) -> tuple[float, float]:
        """(speed factor, angle offset) of the swing (alpha, kappa); (0, 0) without a hit."""
        key = (float(a), float(k))
        if key not in seen:
            try:
                _, launch = swing_launch(scene, ball, key[0], key[1], {"rest_time": 0.0})
            except ValueError as exc:
                failures.append(str(exc))
                launch = None
            else:
                if launch is None:
                    failures.append("the club did not reach the ball")
            if launch is None:
                seen[key] = (0.0, 0.0)
            else:
                c = stroke.club_velocity(key[0], key[1])[0, :2]
                seen[key] = (float(np.linalg.norm(launch) / np.linalg.norm(c)),
                             float(np.arctan2(c[0] * launch[1] - c[1] * launch[0],
                                              c @ launch)))
        return seen[key]

    def table(alphas, kappas):
        m = np.array([[measure(a, k) for a in alphas] for k in kappas])
        return m[..., 0], m[..., 1]

    factor, offset = table(alphas, kappas)
    if check is not None and np.any(factor > 0):
        check(LaunchTable(alphas, kappas, factor, offset, str(scene.robot)))
    for _ in range(max(int(refine), 0)):
        if not np.any(factor > 0):
            break
        trial = LaunchTable(alphas, kappas, factor, offset)
        split_a, split_k = set(), set()
        for i in range(len(kappas) - 1):
            for j in range(len(alphas) - 1):
                if np.any(factor[i:i + 2, j:j + 2] <= 0):
                    continue
                a, k = (alphas[j] + alphas[j + 1]) / 2, (kappas[i] + kappas[i + 1]) / 2
                f, o = measure(a, k)
                fi, oi = (v[0] for v in trial.at(a, k))
                if f <= 0 or abs(fi - f) > REFINE_TOLERANCE * f or abs(oi - o) > \
                        REFINE_TOLERANCE:
                    split_a.add(float(a))
                    split_k.add(float(k))
        if not split_a:
            break
        alphas = np.array(sorted(set(alphas.tolist()) | split_a))
        kappas = np.array(sorted(set(kappas.tolist()) | split_k))
        factor, offset = table(alphas, kappas)
    if not np.any(factor > 0):
        why = max(set(failures), key=failures.count) if failures else "no swing"
        raise ValueError(
            f"the {scene.robot} hits the ball in none of {len(seen)} swings over alpha "
            f"{lo:g}..{hi:g} deg and kappa {klo:g}..{khi:g} at ball "
            f"{np.round(np.asarray(ball, float), 3).tolist()} on {scene.field.name} "
            f"(most often: {why}); give it a base nearer the ball, demonstrations it can "
            f"follow at this scale, or another robot")
    return LaunchTable(alphas, kappas, factor, offset, str(scene.robot))
