"""SEDS in joint space: the shipped putts mapped to the WAM's 7 joints, learned and reproduced.

The paper notes that the formulation works in joint space too. The 7 shipped Cartesian putting
demonstrations are mapped through the WAM's inverse kinematics (each one backwards from the
hitting configuration q*, so all end at q*; ``seds_casadi.robots.joint_space``), SEDS learns a
7-D stable DS with q* as its attractor, and the reproductions from the demonstrations' starts
are integrated. Prints the fit time, e_dot (mean 1 - cos between the model's and the
demonstrated joint velocities) and whether every reproduction reaches q*; draws the seven
joint angles over time (demonstrations dashed, reproductions solid) and the club head's path of
each reproduction (forward kinematics) beside the Cartesian demonstrations.

python examples/joint_space_seds.py [-K 3] [--out examples_out/joint_space_seds.png] [--quick]
"""

import argparse
import os
import time
import warnings

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from seds_casadi import SEDS  # noqa: E402
from seds_casadi.core.metrics import pointwise_direction_error  # noqa: E402
from seds_casadi.motion import load_hitting_demos  # noqa: E402
from seds_casadi.robots import place_robot  # noqa: E402
from seds_casadi.robots.joint_space import joint_space_demos  # noqa: E402

ap = argparse.ArgumentParser()
ap.add_argument("-K", type=int, default=3, help="Gaussians [3]")
ap.add_argument("--out", default="examples_out/joint_space_seds.png",
                help="the figure's file; its folder is made [examples_out/joint_space_seds.png]")
ap.add_argument("--quick", action="store_true", help="K = 2 (for CI)")
args = ap.parse_args()
if args.quick:
    args.K = 2

cart = load_hitting_demos()
robot = place_robot("wam", [0.0, 0.0])
t0 = time.perf_counter()
joints = joint_space_demos(robot, cart)
print(f"IK of {joints.n_samples} samples: {time.perf_counter() - t0:.1f} s; q* = "
      f"{np.round(joints.target, 3).tolist()} rad")
with warnings.catch_warnings():
    warnings.simplefilter("ignore")  # the putts end at the ball with speed: said once below
    model = SEDS(args.K, objective="direction", random_state=0).fit(joints).model_
info = model.fit_info
X, V = np.concatenate(joints.positions), np.concatenate(joints.velocities)
e_dot = float(np.mean(pointwise_direction_error(model.predict(X), V)))
starts = np.stack([p[0] for p in joints.positions])
paths, rinfo = model.rollout(starts, dt=0.01, max_steps=5000, tol=1e-2, return_info=True)
print(f"SEDS K={args.K} in 7-D: {info['seconds']:.1f} s ({info['hessian']} Hessian, "
      f"{info['iterations']} iterations, {info['status']}); e_dot {e_dot:.3f}; "
      f"{int(rinfo['converged'].sum())}/{len(starts)} reproductions reach q* (within 0.01 rad)")

dt = joints.estimated_dt()
fig, axes = plt.subplots(2, 4, figsize=(14, 6), constrained_layout=True)
for j in range(7):
    ax = axes.flat[j]
    for n, (p, r) in enumerate(zip(joints.positions, paths)):
        c = plt.cm.viridis(n / max(1, joints.n_demos - 1))
        ax.plot(np.arange(len(p)) * dt, p[:, j], "--", color=c, lw=1)
        ax.plot(np.arange(len(r)) * 0.01, r[:, j], "-", color=c, lw=1.4)
    ax.axhline(joints.target[j], color="k", lw=0.6, ls=":")
    ax.set_title(f"joint {j + 1}")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("q [rad]")
ax = axes.flat[7]
for n, (p, r) in enumerate(zip(cart.positions, paths)):
    c = plt.cm.viridis(n / max(1, joints.n_demos - 1))
    head = np.array([robot.head_pose(q)[0] for q in r])
    ax.plot(p[:, 0], p[:, 1], "--", color=c, lw=1)
    ax.plot(head[:, 0], head[:, 1], "-", color=c, lw=1.4)
ax.plot(0, 0, "ko", ms=5, label="ball")
ax.plot([], [], "k--", lw=1, label="demonstration")
ax.plot([], [], "k-", lw=1.4, label="reproduction (FK)")
ax.set_title("club head, top view")
ax.set_xlabel("x [m]")
ax.set_ylabel("y [m]")
ax.set_aspect("equal", adjustable="datalim")
ax.legend(fontsize=7)
fig.suptitle(f"WAM joint space: SEDS K={args.K} on the 7 putts mapped by IK "
             f"(dashed: demonstrations; solid: reproductions; dotted: q*); e_dot {e_dot:.3f}")
os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
fig.savefig(args.out, dpi=100)
print(f"wrote {args.out}")
