"""The paper's Katana experiment (Section 7.1, Fig. 7 and 8), on the Katana's own green.

The putting motion is learned with SEDS (K = 3) and a strength factor of 2 components, as in
Section 7.1. The Katana stands beside the ball on ``katana_flat`` (a flat green sized for it:
the hole 0.45 m ahead); its launch of the ball is measured from its own swings
(:func:`seds_casadi.game.launch.calibrate_launch`), the teacher finds good shots on that launch
for the ball moved along y from 0 to -0.18 m, and GPR learns the hitting angle from them. Then,
each shot executed by the 500 Hz controller on the Katana's dynamics (Pinocchio) and rolled on
the ball model, some checked again in exudyn:

* Fig. 7a: the ball moved along y (0 to -0.18 m), the hole fixed on the x axis;
* Fig. 7b: the ball fixed, three hole positions;
* Fig. 8: the ball pushed 3 cm along -y during the swing; the controller reads the ball every
  2 ms and GPR gives the angle for the new situation (no re-planning).

python examples/katana_experiment.py [--out examples_out/katana.png] [--quick]
"""

import argparse
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from seds_casadi.game.launch import calibrate_launch  # noqa: E402
from seds_casadi.game.scene import Scene  # noqa: E402
from seds_casadi.game.shot import Shot, play_shot, play_shots, swing_launch  # noqa: E402
from seds_casadi.minigolf.ball import simulate_shots  # noqa: E402
from seds_casadi.minigolf.fields import load_field  # noqa: E402
from seds_casadi.minigolf.parameters import make_model  # noqa: E402
from seds_casadi.minigolf.teacher import collect_dataset  # noqa: E402
from seds_casadi.motion import HittingMotionLearner, load_hitting_demos  # noqa: E402

ap = argparse.ArgumentParser()
ap.add_argument("--out", default="examples_out/katana.png",
                help="the figure's file; its folder is made [examples_out/katana.png]")
ap.add_argument("--quick", action="store_true", help="fewer cases, one exudyn check (CI)")
args = ap.parse_args()
os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)

motion = HittingMotionLearner(n_components=3, strength_components=2).fit(
    load_hitting_demos()).motion_
field = load_field("katana_flat")
scene = Scene("katana", field, motion)
scene = scene.with_launch(calibrate_launch(scene))   # over the field's teacher's ranges
data = collect_dataset(field, scene.stroke, **({"resolution": (81, 26)} if args.quick else {}))
gpr = make_model("gpr").fit(data.situations, data.outputs)
kappa = float(data.kappa[0])   # the teacher's fixed speed
hole0 = np.asarray(field.hole, float)
print(f"taught {len(data)} situations at kappa {kappa:.2f} ({kappa * motion.hitting_speed:.2f} "
      f"m/s at the club)")


def shot(ball, hole, label):
    a = float(np.deg2rad(gpr.predict((np.asarray(hole) - ball)[None])[0, 0]))
    return Shot(ball, hole, a, kappa, method=label)


def _top_view(ax, title, legend_at):
    """The green from above, the same window in every panel."""
    ax.set_aspect("equal")
    ax.set_xlim(-0.35, 0.55)
    ax.set_ylim(-0.3, 0.3)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.legend(fontsize=7, loc=legend_at)
    ax.set_title(title, fontsize=9)


balls_y = [0.0, -0.18] if args.quick else [0.0, -0.06, -0.12, -0.18]
holes_y = [0.0, 0.16] if args.quick else [0.0, 0.08, 0.16]
cases = {"7a": [shot(np.array([0.0, y]), hole0, f"ball y {y:+.2f}") for y in balls_y],
         "7b": [shot(np.zeros(2), np.array([hole0[0], y]), f"hole y {y:+.2f}") for y in holes_y]}
fig, axs = plt.subplots(1, 3, figsize=(16, 3.9))
print(f"{'case':<14} {'alpha deg':>9} {'dir err deg':>11} {'speed err':>9} {'limits':>6} "
      f"{'sunk':>5} {'exudyn':>6}")
n_exudyn = 1 if args.quick else 3
for ax, (fig7, shots) in zip(axs[:2], cases.items()):
    for k, res in enumerate(play_shots(scene, shots, keep_swing=True)):
        s = res.shot
        ex = play_shot(scene, s, engine="exudyn").sunk if k < n_exudyn else ""
        print(f"{s.method:<14} {np.degrees(s.alpha):9.2f} {res.direction_error_deg:11.3f} "
              f"{res.speed_error:+9.2%} {str(res.within_limits):>6} {str(res.sunk):>5} "
              f"{str(ex):>6}")
        line, = ax.plot(res.swing.head[:, 0], res.swing.head[:, 1], "-", lw=1,
                        label=f"{s.method}: {'sunk' if res.sunk else res.miss}")
        ax.plot(res.path[:, 0], res.path[:, 1], ":", color=line.get_color(), lw=1)
        ax.plot(*s.ball, "o", color="w", mec="k", ms=6)
        ax.add_patch(plt.Circle(s.hole, field.hole_radius, fill=False, color=line.get_color()))
    _top_view(ax, f"Fig. {fig7}: club head (solid) and ball (dotted) from above", "lower right")

# Fig. 8: the ball pushed along -y during the swing; GPR re-aims every tick (no re-planning)
ax = axs[2]
ball0 = np.array([0.0, -0.06])
push = np.array([0.0, -0.03])
z = scene.ball_position(ball0)[2]


def params(t, ball, hole):
    s = np.asarray(hole, float)[:2] - np.asarray(ball, float)[:2]
    return float(np.deg2rad(gpr.predict(s[None])[0, 0])), kappa


times = [None, 0.1] if args.quick else [None, 0.05, 0.1, 0.15, 0.2]
for t in times:
    ev = None if t is None else [{"t": t, "ball": np.r_[ball0 + push, z]}]
    swing, launch = swing_launch(scene, ball0, *params(0.0, ball0, hole0),
                                 {"perturb": ev, "params": params, "hole": hole0})
    pushed = t is not None and t < swing.hit_time   # a push after the hit moves nothing
    start = ball0 + push if pushed else ball0
    label = ("no push" if t is None else f"push at {t:.2f} s"
             + ("" if pushed else f" (after the hit at {swing.hit_time:.2f} s)"))
    line, = ax.plot(swing.head[:, 0], swing.head[:, 1], "-", lw=1)
    sunk = False
    if launch is not None:
        roll = simulate_shots(field, start[None], launch[None], hole=hole0, engine="numpy",
                              record_paths=True)
        sunk = bool(roll.sunk[0])
        ax.plot(roll.paths[0][:, 0], roll.paths[0][:, 1], ":", lw=1, color=line.get_color())
    line.set_label(f"{label}: {'sunk' if sunk else 'missed'}")
    print(f"{'8: ' + label:<14} {'':>9} {swing.direction_error_deg:11.3f} "
          f"{swing.signed_speed_error:+9.2%} {str(swing.within_limits):>6} {str(sunk):>5}")
ax.plot(*ball0, "o", color="w", mec="k", ms=6, label="ball")
ax.plot(*(ball0 + push), "o", color="0.7", mec="k", ms=6, label="ball after the push")
ax.add_patch(plt.Circle(hole0, field.hole_radius, fill=False, color="k"))
_top_view(ax, "Fig. 8: the ball pushed 3 cm along -y during the swing", "upper left")
fig.tight_layout()
fig.suptitle(f"The Katana on katana_flat (SEDS K = 3, strength factor of 2 components, GPR; "
             f"kappa {kappa:.2f})", fontsize=10, y=1.02)
fig.savefig(args.out, dpi=110, bbox_inches="tight")
print(f"wrote {args.out}")
