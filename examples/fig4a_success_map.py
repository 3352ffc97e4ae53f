"""Paper Fig. 4a: success (green) or failure (red) of each (alpha, kappa) for one ball position
on the arctan field, with the teacher's choice; below, the same situation with bank shots and
the strategies coloured (the paper's Section 8 extension: every successful region of the
teacher's situations explored, clustered into strategies consistent across situations,
``seds_casadi.minigolf.strategies``) and each strategy's shot from that ball.

Several separated regions are the different strategies; the teacher keeps the one with the
slowest hits (the paper's choice for arctan, "the lower of the three green fields").

python examples/fig4a_success_map.py [--out examples_out/fig4a.png] [--field arctan] [--strategies 3]
                                     [--quick]
"""

import argparse
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from seds_casadi.app.plotting import plot_field, plot_strategies, plot_success_map
from seds_casadi.minigolf import Stroke, success_map
from seds_casadi.minigolf.ball import simulate_shots
from seds_casadi.minigolf.fields import load_field
from seds_casadi.minigolf.hitting_data import paper_situations
from seds_casadi.minigolf.strategies import explore
from seds_casadi.minigolf.teacher import Teacher
from seds_casadi.motion.hitting import HittingMotionLearner
from seds_casadi.motion.putting_demos import load_hitting_demos

ap = argparse.ArgumentParser()
ap.add_argument("--out", default="examples_out/fig4a.png",
                help="the figure's file; its folder is made [examples_out/fig4a.png]")
ap.add_argument("--field", default="arctan", help="field name or .json file [arctan]")
ap.add_argument("--strategies", default="3", help="'auto' or the number of strategies [3]")
ap.add_argument("--quick", action="store_true", help="a coarser grid for CI")
args = ap.parse_args()
os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)

field = load_field(args.field)
stroke = Stroke.from_motion(HittingMotionLearner().fit(load_hitting_demos()).motion_)
ball = np.array([0.1, -0.3])
hole = field.situations.hole.design(3)[1 if field.situations.hole.kind != "fixed" else 0]
n = 60 if args.quick else 200
alphas = np.deg2rad(np.linspace(-10, 50, n))
kappas = np.linspace(0.6, 2.4, n)
M = success_map(field, stroke, ball, hole, alphas, kappas, banks=False)
alpha, kappa = Teacher(field, stroke).good_shot(ball, hole)
print(f"{M.mean():.1%} of the grid sinks the ball directly; teacher: alpha = "
      f"{np.rad2deg(alpha):.2f} deg, kappa = {kappa:.3f}")

balls, holes = paper_situations(field, 12 if args.quick else None)
strategies = explore(field, stroke, balls, holes,
                     n_strategies=args.strategies if args.strategies == "auto"
                     else int(args.strategies),
                     **({"resolution": (121, 37)} if args.quick else {}))
print(f"{strategies.settings['found']} strategies found over {len(balls)} situations, "
      f"{len(strategies)} kept:\n{strategies.describe()}")

fig = plt.figure(figsize=(15, 9.6))
grid = fig.add_gridspec(2, 2, width_ratios=[1, 1.7], height_ratios=[1, 1.25])
a1 = fig.add_subplot(grid[0, 0])
plot_success_map(M, alphas, kappas, ax=a1, chosen=(alpha, kappa),
                 title=f"Fig. 4a: {field.name}, ball at {ball.tolist()}, direct shots")
# a few direct hits from the map: the teacher's, some sunk and some missed ones
ok = np.argwhere(M)
rng = np.random.default_rng(0)
pick = ok[rng.choice(len(ok), min(5, len(ok)), replace=False)] if len(ok) else np.zeros((0, 2))
A = np.concatenate([[alpha], alphas[pick[:, 1].astype(int)], np.deg2rad([10.0, 25.0])])
K = np.concatenate([[kappa], kappas[pick[:, 0].astype(int)], [1.2, 1.1]])
res = simulate_shots(field, np.tile(ball, (len(A), 1)), stroke.launch_velocity(A, K), hole=hole,
                     record_paths=True, engine="numpy")
a2 = fig.add_subplot(grid[0, 1])
plot_field(field, ax=a2, paths=res.paths, sunk=res.sunk, ball=ball, hole=hole)
a2.set_title(f"{field.name}: direct hits from the map, the teacher's among them",
             fontsize=9)
plot_strategies(field, stroke, strategies, ball, hole, fig.add_subplot(grid[1, 0]),
                fig.add_subplot(grid[1, 1]), chosen=0,
                resolution=(151, 37) if args.quick else None)
fig.savefig(args.out, dpi=110, bbox_inches="tight")
print(f"wrote {args.out}")
