"""Accuracy of the hitting motion (issue 3's acceptance test), printed as figures.

From N random start points in the demonstrated start region (the box around the
demonstrations' first points, turned by alpha with the motion), alpha uniform in [-30, 30] deg and
kappa in [0.5, 1.5]: does every rollout reach the ball, and how far are the hitting direction
from R_alpha psi* and the speed from kappa v*? Then the ball moved +-5 cm mid-swing (t = 0.25 s)
from each demonstration's start.

The hitting velocity is the club's mean velocity over the last control period (2 ms); the
largest angle between the *commanded* velocity and R_alpha psi* over the last centimetre before
the ball is printed too (a stricter reading: what the club is told while it lines up).

Usage: python benchmarks/eval_hitting_accuracy.py [-n 50] [-K 3] [--seed S] [--fit-seed S]
       [--no-approach-paths] [--approach-ratio R]
"""

from __future__ import annotations

import argparse

import numpy as np

from seds_casadi.motion import HittingMotionLearner, load_hitting_demos, rotation_z


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-n", type=int, default=50)
    ap.add_argument("-K", type=int, default=3)
    ap.add_argument("--approach-ratio", type=float, default=None)
    ap.add_argument("--seed", type=int, default=0, help="seed of the random starts")
    ap.add_argument("--fit-seed", type=int, default=0, help="SEDS random_state")
    ap.add_argument("--no-approach-paths", action="store_true",
                    help="the paper's plain SEDS data (no virtual approach paths)")
    args = ap.parse_args()
    demos = load_hitting_demos()
    motion = HittingMotionLearner(n_components=args.K, approach_ratio=args.approach_ratio,
                                  approach_paths=not args.no_approach_paths,
                                  random_state=args.fit_seed).fit(demos).motion_
    lo = np.min([p[0] for p in demos.positions], axis=0)
    hi = np.max([p[0] for p in demos.positions], axis=0)
    rng = np.random.default_rng(args.seed)
    errs, speeds, hits, last_cm = [], [], 0, []
    for _ in range(args.n):
        a = np.deg2rad(rng.uniform(-30, 30))
        k = rng.uniform(0.5, 1.5)
        r = motion.rollout(rotation_z(a) @ rng.uniform(lo, hi), alpha=a, kappa=k)
        if r.hit:
            hits += 1
            errs.append(r.direction_error_deg)
            speeds.append(abs(r.speed_error))
            n = np.searchsorted(r.times, r.hit_time)
            P, V = r.positions[:n] - r.balls[:n], r.velocities[:n]
            near = np.linalg.norm(P, axis=1) < 0.01
            if near.any():
                c = V[near] @ r.commanded_direction / np.linalg.norm(V[near], axis=1)
                last_cm.append(np.degrees(np.arccos(np.clip(c, -1, 1))).max())
    errs, speeds = np.array(errs), np.array(speeds)
    tries = motion.fit_info["tries"]
    print(f"SEDS fits tried: {len(tries)} (kept #{motion.fit_info['kept']}); probe max errors "
          + ", ".join(f"{t.get('max_direction_error_deg', float('nan')):.2f}" for t in tries))
    print(f"K={args.K}, approach_paths={not args.no_approach_paths}, "
          f"approach_ratio={args.approach_ratio}: psi* = "
          f"{np.round(motion.hitting_direction, 3)}, v* = {motion.hitting_speed:.3f} m/s")
    print(f"random starts: {hits}/{args.n} hit the ball")
    print(f"  direction error [deg]: median {np.median(errs):.3f}, max {errs.max():.3f}, "
          f"above 1 deg: {(errs > 1).sum()}/{len(errs)}")
    print(f"  speed error: max {100 * speeds.max():.2f} %")
    lc = np.array(last_cm)
    print(f"  commanded direction over the last cm [deg]: median of max {np.median(lc):.3f}, "
          f"max {lc.max():.3f}, above 1 deg: {(lc > 1).sum()}/{len(lc)}")
    pert = []
    for p in demos.positions:
        for dy in (0.05, -0.05):
            r = motion.rollout(p[0], perturb=[{"t": 0.25, "ball": [0.0, dy, 0.0]}])
            pert.append((r.hit, r.direction_error_deg, abs(r.speed_error)))
    ok = all(h for h, _, _ in pert)
    print(f"ball moved +-5 cm at t = 0.25 s from the {demos.n_demos} demonstration starts: "
          f"all hit: {ok}; direction error max {max(e for _, e, _ in pert):.3f} deg, "
          f"speed error max {100 * max(s for _, _, s in pert):.2f} %")


if __name__ == "__main__":
    main()
