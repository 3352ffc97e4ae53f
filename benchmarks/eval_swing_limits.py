"""Swings a real arm could execute (issue 16): N random swings per robot, checked against the
arm's limits on the simulated motion (not only the reference).

Each swing: a ball position uniform in the field's ball region, alpha uniform in +-30 deg and
kappa uniform over the robot's played range (WAM 0.5-1.5, Katana 0.2-0.45 by default), on the
robot placed beside the ball (:func:`~seds_casadi.robots.placement.place_robot`). Printed per
robot: hits; the peak joint speed and torque against each joint's limit (largest over the
swings, and how many swings broke one); the largest joint speed change in the first 20 ms
(the start step); the direction error of the club velocity at the hit; the launch direction
error (the face's normal, along which the ball leaves, against the commanded direction); and
the median control tick.

Usage: python benchmarks/eval_swing_limits.py [-n 50] [--robots wam katana] [--field flat]
       [--seed 0] [--ik dls|qp] [--no-cartesian-limit]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from seds_casadi.minigolf.fields import load_field
from seds_casadi.motion import BALL_RADIUS, HittingMotionLearner, load_hitting_demos
from seds_casadi.robots import place_robot, simulate_swing

KAPPA = {"wam": (0.5, 1.5), "katana": (0.2, 0.45)}


def _swings(name, motion, field, n, rng, **kw):
    r = field.ball_region
    out = []
    for _ in range(n):
        b = np.array([rng.uniform(r[0], r[1]), rng.uniform(r[2], r[3])])
        a = np.deg2rad(rng.uniform(-30, 30))
        k = rng.uniform(*KAPPA.get(name, (0.5, 1.5)))
        z = float(field.surface.height(b[None])[0]) + BALL_RADIUS
        robot = place_robot(name, b, field)
        out.append((robot, simulate_swing(robot, motion, np.array([b[0], b[1], z]), a, k,
                                          **kw)))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-n", type=int, default=50)
    ap.add_argument("--robots", nargs="+", default=["wam", "katana"])
    ap.add_argument("--field", default="flat")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--ik", default="dls", choices=["dls", "qp"])
    ap.add_argument("--no-cartesian-limit", action="store_true",
                    help="no speed limit on the elbow and the wrist centre")
    args = ap.parse_args()
    ctl = {"ik": args.ik}
    if args.no_cartesian_limit:
        ctl["cartesian_speed_limit"] = None
    motion = HittingMotionLearner(n_components=3).fit(load_hitting_demos()).motion_
    field = load_field(args.field)
    for name in args.robots:
        t0 = time.perf_counter()
        sw = _swings(name, motion, field, args.n, np.random.default_rng(args.seed),
                     controller=ctl)
        speed = np.array([s.speed_ratio for _, s in sw])
        torque = np.array([s.torque_ratio for _, s in sw])
        broken = sum(not s.within_limits for _, s in sw)
        step = np.array([np.max(np.abs(np.diff(s.qd[: int(0.02 / 0.002) + 1], axis=0)))
                         for _, s in sw])
        hits = [s for _, s in sw if s.hit]
        dirs = np.array([s.direction_error_deg for s in hits])
        face = np.array([s.face_error_deg for s in hits])
        ticks = np.concatenate([s.tick_us[1:] for _, s in sw])
        print(f"{name}: {len(hits)}/{len(sw)} hit, {broken} broke a limit "
              f"({time.perf_counter() - t0:.0f} s)")
        print("  peak joint speed / limit, max per joint: "
              + " ".join(f"{v:.2f}" for v in speed.max(axis=0))
              + f"; swings over a limit: {(speed.max(axis=1) > 1 + 1e-6).sum()}")
        print("  peak torque / effort, max per joint:     "  # tau - g(q) for the Katana
              + " ".join(f"{v:.2f}" for v in torque.max(axis=0))
              + f"; swings over a limit: {(torque.max(axis=1) > 1 + 1e-6).sum()}")
        print(f"  largest joint speed change per 2 ms tick in the first 20 ms: "
              f"{step.max():.3f} rad/s")
        print(f"  direction error at the hit [deg]: median {np.median(dirs):.3f}, "
              f"max {dirs.max():.3f}")
        spd = np.array([s.speed_error for s in hits])
        print(f"  speed error at the hit: median {100 * np.median(spd):.2f} %, "
              f"max {100 * spd.max():.2f} %")
        print(f"  launch direction error (face normal) [deg]: median {np.median(face):.3f}, "
              f"max {face.max():.3f}")
        print(f"  control tick: median {np.median(ticks):.1f} us")


if __name__ == "__main__":
    main()
