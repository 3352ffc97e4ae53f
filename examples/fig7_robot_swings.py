"""Paper Fig. 6g and Fig. 7: the hitting motion executed by the WAM and the Katana through the
500 Hz controller (DLS IK + inverse dynamics) on Pinocchio's forward dynamics.

Top: the WAM's motion sequence (Fig. 6g). Bottom: club-head paths seen from above for the ball
moved sideways (Fig. 7a, hole fixed) and for three hole positions (Fig. 7b, ball fixed), each
aimed straight at the hole; the table printed gives the direction and speed errors at impact
against the commanded hitting velocity and the peak torque ratio.

python examples/fig7_robot_swings.py [--out examples_out/fig7.png] [--quick]
"""

import argparse
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from seds_casadi.app.plotting import plot_arm_frames
from seds_casadi.motion import HittingMotionLearner, load_hitting_demos
from seds_casadi.robots import default_base, load_robot, simulate_swing

ap = argparse.ArgumentParser()
ap.add_argument("--out", default="examples_out/fig7.png",
                help="the figure's file; its folder is made [examples_out/fig7.png]")
ap.add_argument("--quick", action="store_true", help="fewer cases for CI")
args = ap.parse_args()
os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)

motion = HittingMotionLearner(n_components=3).fit(load_hitting_demos()).motion_
HOLE_X = 2.4
offsets = [0.0, -0.18] if args.quick else [0.0, -0.06, -0.12, -0.18]
holes = [-0.3, 0.3] if args.quick else [-0.3, 0.0, 0.3]
fig = plt.figure(figsize=(13, 13))
print(f"{'robot':<7} {'case':<22} {'alpha deg':>9} {'dir err deg':>11} {'face err deg':>12} "
      f"{'speed err':>9} {'peak tau':>8}")
for col, (name, kappa) in enumerate((("wam", 1.0), ("katana", 0.4))):
    robot = load_robot(name, base=default_base(name))
    ax3d = fig.add_subplot(2, 2, 1 + col, projection="3d")
    cases = [(f"ball y {dy:+.2f} (7a)", np.array([0.0, dy, 0.02135]), 0.0) for dy in offsets]
    cases += [(f"hole y {hy:+.2f} (7b)", np.array([0.0, 0.0, 0.02135]), hy) for hy in holes]
    for row, fig7 in enumerate(("7a", "7b")):
        ax = fig.add_subplot(4, 2, 5 + 2 * row + col)
        for label, ball, hole_y in cases:
            if not label.endswith(f"({fig7})"):
                continue
            # the angle that turns the default hit psi* towards the hole
            psi = motion.hitting_direction
            alpha = float(np.arctan2(hole_y - ball[1], HOLE_X - ball[0])
                          - np.arctan2(psi[1], psi[0]))
            res = simulate_swing(robot, motion, ball, alpha, kappa)
            print(f"{name:<7} {label:<22} {np.degrees(alpha):9.2f} "
                  f"{res.direction_error_deg:11.2f} {res.face_error_deg:12.2f} "
                  f"{res.speed_error:9.1%} "
                  f"{res.peak_torque_ratio:8.2f}")
            ax.plot(res.head[:, 0], res.head[:, 1], "-", lw=1, label=label[:12])
            ax.plot(ball[0], ball[1], "o", color="w", mec="k", ms=6)
            if fig7 == "7a" and label.startswith("ball y +0.00"):
                k = np.linspace(0, len(res.t) - 1, 7).astype(int)
                plot_arm_frames(robot, res.q[k], ax=ax3d, ball=ball)
                ax3d.set_title(f"Fig. 6g: the {name}'s swing (later frames darker)", fontsize=9)
        ax.set_aspect("equal", adjustable="datalim")   # to scale, filling the panel
        ax.grid(alpha=0.3)
        ax.set_xlabel("club head x [m] (ball at x = 0, hole ahead)")
        ax.set_ylabel("club head y [m]")
        what = ("the ball moved sideways, the hole fixed" if fig7 == "7a"
                else "three hole positions, the ball fixed")
        ax.set_title(f"Fig. {fig7}, the {name}: club-head paths from above, {what}",
                     fontsize=9)
        ax.legend(fontsize=7, title="white dots: balls", title_fontsize=7)
fig.tight_layout()
fig.savefig(args.out, dpi=110, bbox_inches="tight")
print(f"wrote {args.out}")
