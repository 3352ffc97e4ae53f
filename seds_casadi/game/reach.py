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

from ..minigolf.ball import simulate_shots
from ..minigolf.teacher import teacher_ranges
from ..motion.golf import BALL_RADIUS
from ..motion.rotation import rotation_z
from ..robots.placement import place_head, place_robot
from ..robots.speed_bound import hitting_speed_bound
from ..robots.swing import simulate_swing

__all__ = ["unreachable", "check_reach", "fastest_gain", "check_swing_accuracy", "slowest_sink",
           "check_launch_reach"]

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


def slowest_sink(field, balls, hole, max_speed: float = 5.0, speed_step: float = 0.05,
                 half_angle_deg: float = 40.0, angle_step_deg: float = 0.5) -> np.ndarray:
    """The slowest launch speed that sinks each ball into ``hole`` on the field's ball model
    [m/s]: launches swept over speeds (``speed_step`` up to ``max_speed``) and directions
    (within ``half_angle_deg`` of the straight line, every ``angle_step_deg``), direct putts
    only (a wall contact ends a shot). What the field needs of a robot's launch.

    Parameters
    ----------
    field : Field
    balls : array, shape (n, 2)
    hole : array, shape (2,)
    max_speed, speed_step, half_angle_deg, angle_step_deg : float
        The sweep (all positive).

    Returns
    -------
    array, shape (n,)
        The slowest sinking launch speed per ball, to within ``speed_step``; inf where none up
        to ``max_speed`` sinks.
    """
    for name, v in (("max_speed", max_speed), ("speed_step", speed_step),
                    ("half_angle_deg", half_angle_deg), ("angle_step_deg", angle_step_deg)):
        if not (np.isfinite(v) and v > 0):
            raise ValueError(f"{name} must be positive and finite, got {v}")
    B = np.atleast_2d(np.asarray(balls, float))
    h = np.asarray(hole, float).ravel()
    if B.shape[1] != 2 or h.shape != (2,) or not (np.all(np.isfinite(B))
                                                 and np.all(np.isfinite(h))):
        raise ValueError(f"balls must have shape (n, 2) and hole (2,), finite; got "
                         f"{B.shape} and {np.shape(hole)}")
    speeds = np.arange(speed_step, max_speed + 1e-9, speed_step)
    turns = np.deg2rad(np.arange(-half_angle_deg, half_angle_deg + 1e-9, angle_step_deg))
    S, T = (g.ravel() for g in np.meshgrid(speeds, turns, indexing="ij"))
    out = np.full(len(B), np.inf)
    for i, b in enumerate(B):
        a = np.arctan2(h[1] - b[1], h[0] - b[0]) + T
        V = np.column_stack([S * np.cos(a), S * np.sin(a)])
        sunk = simulate_shots(field, np.tile(b, (len(S), 1)), V, hole=h,
                              stop_at_walls=True).sunk
        if np.any(sunk):
            out[i] = float(np.min(S[np.asarray(sunk, bool)]))
    return out


def check_launch_reach(scene, kappa: float, max_short: float = 0.5,
                       top_kappa: float | None = None) -> None:
    """Before teaching: the robot's fastest accurate swing launches the ball fast enough for the
    field. ``ValueError`` when it is too slow for more than ``max_short`` of the declared ball
    positions (a 3 x 3 spread over a region, nine points along a slider), saying what it lacks.

    The robot swings once at gain ``kappa`` (:func:`fastest_gain`: its fastest swing within
    2 % of the commanded speed) at the middle declared ball, straight at the middle declared
    hole; its launch is the impact of :func:`~seds_casadi.game.shot.swing_launch` (the arm's
    effective mass at the face). The field's need is :func:`slowest_sink` at each declared ball.
    The message gives the club speed, the launch, how far that launch rolls, the field's need,
    and the physical ceiling at the hit: the joints' velocity limits' bound on the club speed
    there (:func:`~seds_casadi.robots.speed_bound.hitting_speed_bound`) and the launch it would
    give. An arm that misses the ball is left to :func:`check_swing_accuracy`.

    A swing faster than ``kappa`` is inaccurate in speed but its launch is measured for the
    teacher all the same (:func:`~seds_casadi.game.launch.calibrate_launch`): before refusing,
    the robot swings once more at ``top_kappa`` (default the top of the field's teacher's
    ``kappa_range``), and that launch counts when the swing stays within 2 deg of the aim.
    """
    from .shot import swing_launch

    if not (np.isfinite(kappa) and kappa > 0):
        raise ValueError(f"kappa must be a positive speed gain, got {kappa}")
    if not 0 <= max_short < 1:
        raise ValueError(f"max_short must be a share in [0, 1), got {max_short}")
    fld = scene.field
    sit = fld.situations.ball
    balls = sit.design(9)
    ball = balls[4 if sit.kind != "fixed" else 0]
    holes = fld.situations.hole.design(3)
    hole = holes[len(holes) // 2]
    alpha = float(scene.stroke.aim(hole - ball)[0])
    swing, launch = swing_launch(scene, ball, alpha, float(kappa), {"rest_time": 0.0})
    if launch is None:
        return
    speed = float(np.linalg.norm(launch))
    need = slowest_sink(fld, balls, hole, max_speed=speed)
    short = int(np.sum(~np.isfinite(need)))
    if short <= max_short * len(balls):
        return
    top = float(teacher_ranges(fld)[1][1] if top_kappa is None else top_kappa)
    faster = ""
    if top > kappa:
        sw2, launch2 = swing_launch(scene, ball, alpha, top, {"rest_time": 0.0})
        if launch2 is None:
            faster = f" (swung at kappa {top:g} it misses the ball)"
        elif sw2.direction_error_deg > 2.0:
            faster = (f" (swung at kappa {top:g} it goes {sw2.direction_error_deg:.0f} deg off "
                      f"the aim)")
        else:
            speed2 = float(np.linalg.norm(launch2))
            faster = f" (swung at kappa {top:g} at {speed2:.2f} m/s)"
            if speed2 > speed:
                need = slowest_sink(fld, balls, hole, max_speed=speed2)
                short = int(np.sum(~np.isfinite(need)))
                if short <= max_short * len(balls):
                    return
    # the field's need at the probed ball (beyond the robot's launch) and how far it rolls
    need_here = float(slowest_sink(fld, ball[None], hole, max_speed=6.0, speed_step=0.02)[0])
    rolled = simulate_shots(fld, ball[None], launch[None], hole=hole).final_position[0]
    # the ceiling: the joints' velocity limits at the hit configuration, along the hit
    i = int(np.argmin(np.abs(swing.t - swing.hit_time)))
    d = np.array([*swing.commanded[:2], 0.0])
    bound = hitting_speed_bound(scene.robot_at(ball), swing.q[i], d)
    n = swing.face_normal / np.linalg.norm(swing.face_normal)
    ceiling = speed * bound.speed * abs(n @ d) / np.linalg.norm(d) / max(
        abs(swing.hit_velocity @ n), 1e-12)
    club = float(np.linalg.norm(swing.hit_velocity))
    dist = float(np.linalg.norm(hole - ball))
    needs = (f"at least {need_here:.2f} m/s" if np.isfinite(need_here)
             else "more than 6 m/s")
    verdict = ("so no controller sinks these putts from this base"
               if not ceiling >= need_here else
               "a controller that reached it might, this one does not accurately")
    raise ValueError(
        f"the {scene.robot} cannot putt far enough on {fld.name}: its fastest accurate swing "
        f"(within 2 % of the commanded speed: kappa {kappa:.2f}, a club speed of {club:.2f} m/s "
        f"at ball {np.round(ball, 3).tolist()}) launches the ball at {speed:.2f} m/s{faster}, "
        f"which rolls {np.linalg.norm(rolled - ball):.2f} m of the {dist:.2f} m to the hole; "
        f"{short} of the {len(balls)} declared ball positions need a faster launch, this one "
        f"{needs}. At the hit the joints' velocity limits allow at most {bound.speed:.2f} m/s "
        f"of club speed along the hit ({_joints(bound.saturated)}), a "
        f"launch of at most {ceiling:.2f} m/s: {verdict}. Declare situations nearer the hole "
        f"(or a field sized for this arm), a faster green, or use another robot")


def _joints(saturated) -> str:
    """'joint 3 at its limit', 'joints 3, 5 at their limits' (1-based)."""
    names = [str(j + 1) for j in saturated]
    if not names:
        return "no joint at its limit"
    if len(names) == 1:
        return f"joint {names[0]} at its limit"
    return f"joints {', '.join(names)} at their limits"
