"""Paper Fig. 4a: success (green) or failure (red) of each (alpha, kappa) for one ball position
on the arctan field, with the ball paths of a few hits and the teacher's choice.

Several separated green regions are the different strategies; the teacher keeps the one with
the slowest hits (the paper's choice for arctan).

python examples/fig4a_success_map.py [--out fig4a.png] [--quick]
"""

import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from seds_casadi.app.plotting import plot_field, plot_success_map
from seds_casadi.minigolf.ball import simulate_shots
from seds_casadi.minigolf.fields import load_field
from seds_casadi.minigolf.teacher import Stroke, Teacher, success_map
from seds_casadi.motion.hitting import HittingMotion
from seds_casadi.motion.putting_demos import load_hitting_demos

ap = argparse.ArgumentParser()
ap.add_argument("--out", default="fig4a.png")
ap.add_argument("--field", default="arctan", help="field name or .json file [arctan]")
ap.add_argument("--quick", action="store_true", help="a coarser grid for CI")
args = ap.parse_args()

field = load_field(args.field)
stroke = Stroke.from_motion(HittingMotion.fit(load_hitting_demos()))
ball = np.array([0.1, -0.3])
n = 60 if args.quick else 200
alphas = np.deg2rad(np.linspace(-40, 40, n))
kappas = np.linspace(0.8, 2.4, n)
M = success_map(field, stroke, ball, field.hole, alphas, kappas)
alpha, kappa = Teacher(field, stroke).good_shot(ball, field.hole)
print(f"{M.mean():.1%} of the grid sinks the ball; teacher: alpha = {np.rad2deg(alpha):.2f} "
      f"deg, kappa = {kappa:.3f}")

fig, (a1, a2) = plt.subplots(1, 2, figsize=(13, 4.2), gridspec_kw={"width_ratios": [1, 1.6]})
plot_success_map(M, alphas, kappas, ax=a1, chosen=(alpha, kappa),
                 title=f"Fig. 4a: {field.name}, ball at {ball.tolist()}")
# a few hits: the teacher's and some sunk and missed ones from the map
ok = np.argwhere(M)
rng = np.random.default_rng(0)
pick = ok[rng.choice(len(ok), min(6, len(ok)), replace=False)] if len(ok) else np.zeros((0, 2))
A = np.concatenate([[alpha], alphas[pick[:, 1].astype(int)], np.deg2rad([-5.0, 12.0])])
K = np.concatenate([[kappa], kappas[pick[:, 0].astype(int)], [1.4, 1.8]])
res = simulate_shots(field, np.tile(ball, (len(A), 1)), stroke.launch_velocity(A, K),
                     record_paths=True, engine="numpy")
plot_field(field, ax=a2, paths=res.paths, sunk=res.sunk, ball=ball)
a2.set_title("ball paths (green: sunk, red: missed)", fontsize=9)
fig.savefig(args.out, dpi=110, bbox_inches="tight")
print(f"wrote {args.out}")
