"""Can the Katana putt on a 3.3 m field? (issue 28) The joints' velocity limits' bound on the
club speed and on the ball's launch, at the default base and over base placements.

1. **At the default base** (:func:`~seds_casadi.robots.placement.default_base`: 0.45 m to +y of
   the ball, 0.1 m up, facing -y), for the three balls ``play``'s accuracy check probes on a field
   (first, middle, last of the declared 3 x 3 spread), aiming at the hole: the hit configuration
   (:func:`~seds_casadi.robots.placement.place_head`), the largest club speed along the aim its
   joints' velocity limits allow (:func:`~seds_casadi.robots.speed_bound.hitting_speed_bound`),
   the arm's effective mass at the face there and the largest launch it gives (the impact model,
   (1 + e) m / (m + m_ball) v.n), against the field's need
   (:func:`~seds_casadi.game.reach.slowest_sink`).
2. **Over base placements**: every hit configuration q of the arm (sampled uniformly within the
   joint limits less 0.15 rad, then the best refined by SLSQP) defines a placement relative to
   the ball: the face's normal gives the hitting direction d, the club head one ball radius
   behind the ball's centre, the base's height so that the ball rests on the field (J1 and the
   base's yaw are the same freedom). Kept are placements where the base is 0 to ``zmax`` above
   the field, every joint origin 5 cm above it, the face tilted at most 15 deg, the backswing
   (0.3 m behind the ball along d) 0.12 m clear of the base's axis and the ball's path 0.1 m
   clear of it; maximised is the launch bound. Printed per ``zmax``: the bound, the club speed
   and effective mass, the placement (distance of the ball from the base's axis, the bearing of
   the base from the ball against d), and an estimate of what the efforts allow: the largest
   club acceleration along d at rest with |tau - g| within the efforts (a linear program),
   a_max, and sqrt(2 a_max 0.3 m), the speed a constant a_max gives over the 0.3 m backswing.

Usage: python benchmarks/eval_katana_speed_bound.py [--field flat] [--zmax 0.1 0.2 0.3 0.45]
       [--samples 15000] [--club-length 0.2] [--head-mass 0.03] [--seed 5]
"""

from __future__ import annotations

import argparse

import numpy as np
import pinocchio as pin
from scipy.optimize import linprog, minimize

from seds_casadi.game.reach import slowest_sink
from seds_casadi.minigolf.ball import impact
from seds_casadi.minigolf.fields import load_field
from seds_casadi.motion import BALL_RADIUS
from seds_casadi.robots import Club, effective_mass, load_robot, place_head, place_robot
from seds_casadi.robots.speed_bound import hitting_speed_bound

MARGIN = 0.15       # [rad] inside the joint limits
BACKSWING = 0.3     # [m] simulate_swing's default start behind the contact point


def launch_factor(m: float) -> float:
    """|launch| / |club speed| of a central impact with effective mass m (minigolf.ball.impact)."""
    return float(impact(np.array([1.0, 0.0]), club_mass=m)[0])


def acceleration_bound(robot, q, d) -> float:
    """Largest club acceleration along d at rest with |tau - g| <= effort, the face held."""
    M = pin.crba(robot.model, robot.data, q)
    M = np.triu(M) + np.triu(M, 1).T
    J = robot.head_jacobian(q)
    A = np.vstack([J[:3], J[5:6]]) @ np.linalg.inv(M)
    n = robot.nv
    Aeq = np.zeros((4, n + 1))
    Aeq[:, :n], Aeq[:3, n] = A, -d
    c = np.zeros(n + 1)
    c[n] = -1
    res = linprog(c, A_eq=Aeq, b_eq=np.zeros(4),
                  bounds=[(-e, e) for e in robot.effort] + [(0, None)], method="highs")
    return float(res.x[n]) if res.status == 0 else 0.0


def placement(robot, q) -> dict:
    """The placement the hit configuration q defines (module docstring, step 2)."""
    p, R = robot.head_pose(q)
    n = R[:, 0]
    d = np.array([n[0], n[1], 0.0]) / np.hypot(n[0], n[1])
    base_z = BALL_RADIUS - p[2]
    ball = p[:2] + BALL_RADIUS * d[:2]
    rel = -ball                                   # the base's axis seen from the ball
    t = np.linspace(0, BACKSWING, 31)
    clear = float(np.min(np.linalg.norm(p[:2][None] - t[:, None] * d[None, :2], axis=1)))
    ahead = rel @ d[:2]
    lateral = abs(d[0] * rel[1] - d[1] * rel[0])
    pin.forwardKinematics(robot.model, robot.data, q)
    zmin = min(robot.data.oMi[j].translation[2] for j in range(2, robot.model.njoints)) + base_z
    return dict(d=d, n=n, base_z=base_z, dist=float(np.linalg.norm(ball)),
                bearing=float(np.degrees(np.arctan2(d[0] * rel[1] - d[1] * rel[0], ahead))),
                clear=clear, path=lateral if ahead > 0 else np.inf, zmin=zmin,
                tilt=float(np.degrees(np.arcsin(np.clip(n[2], -1, 1)))))


def constraints(robot, q, zmax) -> np.ndarray:
    g = placement(robot, q)
    return np.array([g["base_z"], zmax - g["base_z"], g["clear"] - 0.12,
                     min(g["path"] - 0.1, 1.0), g["zmin"] - 0.05, 15 - abs(g["tilt"])])


def launch_bound(robot, q) -> tuple[float, float, float]:
    """(launch bound, club speed bound, effective mass) at the hit configuration q."""
    g = placement(robot, q)
    s = hitting_speed_bound(robot, q, g["d"]).speed
    m = effective_mass(robot, q, g["n"])
    return launch_factor(m) * s * float(g["n"] @ g["d"]), s, m


def best_placement(robot, zmax, samples, rng):
    lo, hi = robot.lower + MARGIN, robot.upper - MARGIN
    cands = []
    for _ in range(samples):
        q = rng.uniform(lo, hi)
        if np.all(constraints(robot, q, zmax) >= 0):
            cands.append((launch_bound(robot, q)[0], q))
    cands.sort(key=lambda c: -c[0])
    best = None
    for _, q0 in cands[:12]:
        res = minimize(lambda q: -launch_bound(robot, q)[0], q0, method="SLSQP",
                       bounds=list(zip(lo, hi)), options=dict(maxiter=200),
                       constraints=[dict(type="ineq",
                                         fun=lambda q: constraints(robot, q, zmax))])
        q = np.clip(res.x, lo, hi)
        if np.all(constraints(robot, q, zmax) >= -1e-6):
            L = launch_bound(robot, q)[0]
            if best is None or L > best[0]:
                best = (L, q)
    return best, len(cands)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--field", default="flat")
    ap.add_argument("--zmax", type=float, nargs="+", default=[0.1, 0.2, 0.3, 0.45])
    ap.add_argument("--samples", type=int, default=15000)
    ap.add_argument("--club-length", type=float, default=0.2)
    ap.add_argument("--head-mass", type=float, default=0.03)
    ap.add_argument("--seed", type=int, default=5)
    args = ap.parse_args()
    club = Club(args.club_length, 0.01, args.head_mass)
    fld = load_field(args.field)
    balls = fld.situations.ball.design(9)
    holes = fld.situations.hole.design(3)
    hole = holes[len(holes) // 2]
    need = slowest_sink(fld, balls, hole, speed_step=0.02)
    print(f"{args.field}: the slowest sinking launch per declared ball [m/s]: "
          + ", ".join(f"{np.round(b, 2).tolist()} {v:.2f}" for b, v in zip(balls, need)))
    print(f"the katana with a {club.length} m club, {club.head_mass} kg head, at its default "
          f"base:")
    for b in balls[::4]:
        r = place_robot("katana", b, fld, club=club)
        d = np.array([*(hole - b), 0.0])
        d /= np.linalg.norm(d)
        z = BALL_RADIUS + float(fld.surface.height(b[None])[0])
        try:
            q = place_head(r, np.array([*b, z]) - BALL_RADIUS * d, d)
        except ValueError as exc:
            print(f"  ball {np.round(b, 2).tolist()}: {exc}")
            continue
        bound = hitting_speed_bound(r, q, d)
        n = r.head_pose(q)[1][:, 0]
        m = effective_mass(r, q, n)
        print(f"  ball {np.round(b, 2).tolist()}: club <= {bound.speed:.3f} m/s (joints "
              f"{[j + 1 for j in bound.saturated]} at their limits), effective mass {m:.3f} kg, "
              f"launch <= {launch_factor(m) * bound.speed * (n @ d):.2f} m/s; a_max "
              f"{acceleration_bound(r, q, d):.1f} m/s^2")
    robot = load_robot("katana", club=club)
    print("over base placements (module docstring):")
    for zmax in args.zmax:
        found, n_ok = best_placement(robot, zmax, args.samples, np.random.default_rng(args.seed))
        if found is None:
            print(f"  base up to {zmax:.2f} m: no placement")
            continue
        L, q = found
        g = placement(robot, q)
        _, s, m = launch_bound(robot, q)
        a = acceleration_bound(robot, q, g["d"])
        print(f"  base up to {zmax:.2f} m ({n_ok} of {args.samples} samples kept): launch <= "
              f"{L:.2f} m/s (club {s:.2f} m/s, effective mass {m:.3f} kg); base {g['base_z']:.2f}"
              f" m up, ball {g['dist']:.2f} m from its axis, base bearing {g['bearing']:+.0f} deg"
              f" from the hit; a_max {a:.1f} m/s^2 -> {np.sqrt(2 * a * BACKSWING):.2f} m/s "
              f"over {BACKSWING} m; q {np.round(q, 3).tolist()}")


if __name__ == "__main__":
    main()
