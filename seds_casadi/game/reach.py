"""Can the robot play the situations a field declares? A check before any swing is simulated.

The robot stands at its default place beside each ball
(:func:`~seds_casadi.robots.placement.place_robot`); a ball it cannot reach, or a start of the
swing (0.3 m behind the ball, 5 cm up, turned by alpha: the default of
:func:`~seds_casadi.robots.swing.simulate_swing`) where the club head cannot be placed, makes
those situations unplayable. :func:`check_reach` names them and says what to change.
:func:`fastest_gain` measures how fast the robot can swing: the largest speed gain kappa it
executes within 2 % of the commanded club speed (its joint velocity and torque limits cap the
rest); :func:`check_swing_accuracy` that it follows the motion's direction at the hit.
"""

from __future__ import annotations

import numpy as np

from ..motion.golf import BALL_RADIUS
from ..motion.rotation import rotation_z
from ..robots.placement import place_head, place_robot
from ..robots.swing import simulate_swing

__all__ = ["unreachable", "check_reach", "fastest_gain", "check_swing_accuracy"]

_START = np.array([-0.3, 0.0, 0.05])  # simulate_swing's default start, relative to the contact


def unreachable(robot: str, field, balls, alphas, direction) -> list[tuple[np.ndarray, str]]:
    """The balls (with the hit's angle) the robot cannot play, and why.

    Parameters
    ----------
    robot : str
        Robot name or ``.urdf`` file.
    field : Field
    balls : array, shape (n, 2)
    alphas : array, shape (n,)
        Hitting angles [rad].
    direction : array, shape (3,)
        The motion's default hitting direction psi*.

    Returns
    -------
    list of (ball (2,), reason)
    """
    bad = []
    d = np.asarray(direction, float)
    for b, a in zip(np.atleast_2d(balls), np.atleast_1d(alphas)):
        z = float(field.surface.height(np.asarray(b, float)[None])[0]) + BALL_RADIUS
        ball = np.array([b[0], b[1], z])
        psi = rotation_z(float(a)) @ d
        contact = ball - BALL_RADIUS / np.hypot(psi[0], psi[1]) * np.array([psi[0], psi[1], 0])
        try:
            r = place_robot(robot, b, field)
            r.check_reach(ball)
            place_head(r, contact + rotation_z(float(a)) @ _START, psi)
        except ValueError as exc:
            bad.append((np.asarray(b, float), str(exc)))
    return bad


def check_reach(robot: str, field, balls, alphas, direction, what: str) -> None:
    """``ValueError`` naming the situations of ``what`` (e.g. "declared ball positions") the
    robot cannot play (:func:`unreachable`) and what to change; nothing when all are fine."""
    bad = unreachable(robot, field, balls, alphas, direction)
    if not bad:
        return
    shown = "; ".join(f"ball {np.round(b, 3).tolist()}: {why}" for b, why in bad[:4])
    more = f" and {len(bad) - 4} more" if len(bad) > 4 else ""
    raise ValueError(f"the {robot} cannot play {len(bad)} of {len(np.atleast_2d(balls))} "
                     f"{what} on {field.name}: {shown}{more}. Declare situations it can reach "
                     f"(the field file's 'situations' or 'ball_region'), or use another robot")


def fastest_gain(robot: str, field, motion, ball=None, tolerance: float = 0.02,
                 kappa_range=(0.2, 2.4), iterations: int = 7) -> float:
    """The largest speed gain the robot swings within ``tolerance`` of the commanded club
    speed (Eq. 14's kappa v*), found by bisection over ``kappa_range`` with swings on the
    robot's dynamics (:func:`~seds_casadi.robots.swing.simulate_swing`; a straight swing at
    ``ball``, default the middle of the declared ball positions). Returns the range's low end
    when even that is too fast, its high end when nothing in it is."""
    if ball is None:
        ball = field.situations.ball.design(9)[4 if field.situations.ball.kind != "fixed"
                                               else 0]
    b = np.asarray(ball, float)
    z = float(field.surface.height(b[None])[0]) + BALL_RADIUS

    def ok(kappa):
        sw = simulate_swing(place_robot(robot, b, field), motion, np.array([b[0], b[1], z]),
                            0.0, float(kappa))
        return sw.hit and sw.speed_error <= tolerance

    lo, hi = (float(v) for v in kappa_range)
    if ok(hi):
        return hi
    if not ok(lo):
        return lo
    for _ in range(int(iterations)):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if ok(mid) else (lo, mid)
    return lo


def check_swing_accuracy(scene, kappa: float, max_error_deg: float = 2.0) -> None:
    """Before teaching: the robot follows the hitting motion at the field's declared ball
    positions (three of the nine the reach check uses: first, middle, last), swinging straight
    at the middle declared hole with gain ``kappa``; ``ValueError`` naming the direction errors
    at the hit when one is above ``max_error_deg`` or the club misses the ball (an arm that
    swings tens of degrees off, like the UR3 at the shipped putts' scale, would be taught shots
    it cannot play)."""
    from .shot import Shot, play_shots

    balls = scene.field.situations.ball.design(9)[::4]
    holes = scene.field.situations.hole.design(3)
    hole = holes[len(holes) // 2]
    shots = [Shot(b, hole, float(scene.stroke.aim(hole - b)[0]), float(kappa)) for b in balls]
    results = play_shots(scene, shots)
    bad = [r for r in results if not r.hit or r.direction_error_deg > max_error_deg]
    if not bad:
        return
    errs = ", ".join(f"ball {np.round(r.shot.ball, 3).tolist()}: "
                     + (f"{r.direction_error_deg:.1f} deg" if r.hit else r.reason)
                     for r in results)
    raise ValueError(
        f"the {scene.robot} does not follow the hitting motion on {scene.field.name} at kappa "
        f"{kappa:.2f} (direction error at the hit above {max_error_deg:g} deg, or no hit: "
        f"{errs}): demonstrations at a scale this arm can follow, another base or another "
        f"robot")
