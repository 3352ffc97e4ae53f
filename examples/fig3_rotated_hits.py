"""Paper Fig. 3: hitting motions turned by an angle alpha (Eq. 14), seen from above.

The default motion (alpha = 0) and two rotated ones, each from several starts; arrows show the
commanded hitting direction R_alpha psi*.

python examples/fig3_rotated_hits.py [--out examples_out/fig3.png] [--quick]
"""

import argparse
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from seds_casadi.motion import HittingMotionLearner, load_hitting_demos, rotation_z

ap = argparse.ArgumentParser()
ap.add_argument("--out", default="examples_out/fig3.png",
                help="the figure's file; its folder is made [examples_out/fig3.png]")
ap.add_argument("--quick", action="store_true", help="fewer starts for CI")
args = ap.parse_args()
os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)

demos = load_hitting_demos()
motion = HittingMotionLearner().fit(demos).motion_
starts = [p[0] for p in demos.positions][: 3 if args.quick else 7]
fig, ax = plt.subplots(figsize=(6, 5.5))
for alpha, colour in ((0.0, "k"), (np.deg2rad(25), "tab:blue"), (np.deg2rad(-25), "tab:orange")):
    for s in starts:
        r = motion.rollout(rotation_z(alpha) @ s, alpha=alpha, rest_time=0.15)
        ax.plot(r.positions[:, 0], r.positions[:, 1], "-", color=colour, lw=1)
    d = rotation_z(alpha) @ motion.hitting_direction
    ax.arrow(0, 0, 0.15 * d[0], 0.15 * d[1], color=colour, width=0.004,
             label=f"alpha = {np.degrees(alpha):+.0f} deg")
ax.plot(0, 0, "o", color="w", mec="k", ms=10)
ax.set_aspect("equal")
ax.set_xlabel("x [m]")
ax.set_ylabel("y [m]")
ax.legend(fontsize=8)
ax.set_title("Fig. 3: hitting direction turned by alpha (Eq. 14)")
fig.savefig(args.out, dpi=110, bbox_inches="tight")
print(f"wrote {args.out}")
