"""Paper Fig. 6 (c)-(f): reproductions of the hitting motion against the demonstrations, and the
velocity profiles along x, y and z.

python examples/fig6_reproductions.py [--out examples_out/fig6.png] [--quick]
"""

import argparse
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from seds_casadi.motion import HittingMotionLearner, load_hitting_demos

ap = argparse.ArgumentParser()
ap.add_argument("--out", default="examples_out/fig6.png",
                help="the figure's file; its folder is made [examples_out/fig6.png]")
ap.add_argument("--quick", action="store_true", help="fewer demonstrations for CI")
args = ap.parse_args()
os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)

demos = load_hitting_demos()
motion = HittingMotionLearner().fit(demos).motion_
n = 3 if args.quick else demos.n_demos
fig = plt.figure(figsize=(12, 7))
ax3 = fig.add_subplot(2, 2, 1, projection="3d")
axes = [fig.add_subplot(2, 2, i) for i in (2, 3, 4)]
dt_demo = 0.05
for p, v in list(zip(demos.positions, demos.velocities))[:n]:
    r = motion.rollout(p[0], rest_time=0.0)
    swing = r.times <= r.hit_time
    ax3.plot(*p.T, ".", color="tab:red", ms=3)
    ax3.plot(*r.positions[swing].T, "-", color="tab:blue", lw=1)
    t_demo = dt_demo * (np.arange(len(p)) - (len(p) - 1))  # time to the hit (20 Hz samples)
    t_rep = r.times[swing] - r.hit_time
    for j, ax in enumerate(axes):
        ax.plot(t_demo, v[:, j], ".", color="tab:red", ms=3)
        ax.plot(t_rep, r.velocities[swing, j], "-", color="tab:blue", lw=1)
ax3.plot([0], [0], [0], "ko")
ax3.set(xlabel="x [m]", ylabel="y [m]", zlabel="z [m]")
ax3.set_title("(c) club-head paths relative to the ball (black): reproductions (blue),\n"
              "demonstrations (red)", fontsize=9)
key = [plt.Line2D([], [], ls="", marker=".", color="tab:red", label="demonstrations (20 Hz)"),
       plt.Line2D([], [], color="tab:blue", label="reproductions (the learned motion)")]
for j, (ax, name) in enumerate(zip(axes, "xyz")):
    ax.set_title(f"({'def'[j]}) club-head velocity along {name}", fontsize=9)
    ax.set_xlabel("time to the hit [s]")
    ax.set_ylabel(f"velocity {name} [m/s]")
    ax.grid(alpha=0.3)
axes[0].legend(handles=key, fontsize=8, loc="upper left")
fig.suptitle("Fig. 6: the hitting motion learned from the shipped putting demonstrations",
             fontsize=10)
fig.tight_layout()
fig.savefig(args.out, dpi=110, bbox_inches="tight")
print(f"wrote {args.out}")
