"""Quick start: learn a stable DS from LASA demonstrations and draw its streamlines.

python examples/quickstart.py [--out examples_out/quickstart.png] [--quick]
"""

import argparse
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from seds_casadi import SEDS  # noqa: E402
from seds_casadi.app.plot_ds import plot_streamlines
from seds_casadi.core.datasets import load_lasa

ap = argparse.ArgumentParser()
ap.add_argument("--out", default="examples_out/quickstart.png",
                help="the figure's file; its folder is made [examples_out/quickstart.png]")
ap.add_argument("--quick", action="store_true", help="smaller data for CI")
args = ap.parse_args()
os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)

demos = load_lasa("CShape", n_samples=30 if args.quick else 100)
learner = SEDS(n_components=3 if args.quick else 5, objective="direction", random_state=0)
model = learner.fit(demos).model_  # the certified StableDS
print(model, model.fit_info["status"], f"{model.fit_info['seconds']:.2f} s")

starts = [p[0] for p in demos.positions]
paths = model.rollout(starts, dt=0.05, tol=1.0)
fig, ax = plt.subplots(figsize=(5, 4.5))
plot_streamlines(model, demos, paths, ax=ax, title="LASA CShape, SEDS direction objective",
                 unit="mm")
fig.savefig(args.out, dpi=110, bbox_inches="tight")
print(f"wrote {args.out}")
