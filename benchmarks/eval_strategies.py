"""Several strategies (the paper's Section 8 extension, issue 15): the strategy chosen per
situation against each single strategy, on the same random situations.

Explores the teacher's situations of a field (bank shots allowed), clusters the successful
regions into strategies (``seds_casadi.minigolf.strategies``), learns one hitting-parameter
model per strategy and a model of each strategy's robustness (``strategy_choice``), then plays
``--situations`` random situations drawn from the field's declaration on the ball model: every
strategy's prediction at every situation, and the chosen one. Also the single-strategy teacher
of the field (its "teacher" entry; minimal speed on arctan) with the same learner.

python benchmarks/eval_strategies.py [--field arctan] [--strategies auto] [--learner gpr]
                                     [--situations 100] [--seed 0]
"""

import argparse
import time

import numpy as np

from seds_casadi.minigolf import Stroke, collect_dataset
from seds_casadi.minigolf.ball import simulate_shots
from seds_casadi.minigolf.fields import load_field
from seds_casadi.minigolf.hitting_data import paper_situations
from seds_casadi.minigolf.parameters import make_model
from seds_casadi.minigolf.strategies import explore
from seds_casadi.minigolf.strategy_choice import StrategyChoice
from seds_casadi.motion.hitting import HittingMotionLearner
from seds_casadi.motion.putting_demos import load_hitting_demos

ap = argparse.ArgumentParser()
ap.add_argument("--field", default="arctan")
ap.add_argument("--strategies", default="auto", help="'auto' or a number")
ap.add_argument("--learner", default="gpr", choices=["gpr", "gmr", "sep_gmr"])
ap.add_argument("--situations", type=int, default=100)
ap.add_argument("--seed", type=int, default=0)
args = ap.parse_args()
n_strategies = args.strategies if args.strategies == "auto" else int(args.strategies)

field = load_field(args.field)
stroke = Stroke.from_motion(HittingMotionLearner(n_components=3).fit(load_hitting_demos()).motion_)
t0 = time.perf_counter()
ss = explore(field, stroke, *paper_situations(field), n_strategies=n_strategies)
print(f"explored {len(ss.ball)} situations in {time.perf_counter() - t0:.1f} s: "
      f"{ss.settings['found']} strategies found, {len(ss)} kept")
print(ss.describe())
choice = StrategyChoice(args.learner).fit(ss)
balls, holes = field.situations.sample(args.situations, np.random.default_rng(args.seed))
S = holes - balls


def sunk(P):
    ok = np.isfinite(P).all(axis=1) & (P[:, 1] > 0)
    out = np.zeros(len(P), bool)
    V = stroke.launch_velocity(np.deg2rad(P[ok, 0]), P[ok, 1])
    out[ok] = simulate_shots(field, balls[ok], V, hole=holes[ok]).sunk
    return out


each = np.column_stack([sunk(choice.predict_strategy(S, k)) for k in range(len(ss))])
P, chosen, _ = choice.predict(S, return_choice=True)
picked = sunk(P)
single = collect_dataset(field, stroke)
model = make_model(args.learner, **({} if args.learner == "gpr" else {"n_components": 3}))
Q = model.fit(single.situations, single.outputs).predict(S)
if Q.shape[1] == 1:
    Q = np.column_stack([Q[:, 0], np.full(len(Q), single.kappa[0])])
print(f"\n{args.situations} random situations on {field.name}, {args.learner} (seed {args.seed}):")
for k, s in enumerate(ss.strategies):
    share = np.mean(chosen == s.label)
    print(f"  strategy {s.label} alone ({ss.strategies[k].describe().split(': ')[1]}): "
          f"{each[:, k].mean():.0%} sunk; chosen for {share:.0%} of the situations, sank "
          f"{picked[chosen == s.label].mean() if share else float('nan'):.0%} of those")
print(f"  the strategy chosen per situation: {picked.mean():.0%} sunk")
print(f"  some strategy's own prediction sinks (the best a choice could do): "
      f"{each.any(axis=1).mean():.0%}")
print(f"  the field's single-strategy teacher ({single.strategy}): {sunk(Q).mean():.0%} sunk")
