"""Choosing SEDS's settings on held-out demonstrations: DemoSearchCV picks the objective and the
Lyapunov function for a LASA shape by reproducing demonstrations it left out; the figure shows
each candidate's held-out RMSE, e_dot and DTW (as ratios to the best candidate's) and the
chosen model's streamlines with every demonstration reproduced.

python examples/choose_settings.py [--shape Leaf_1] [--out examples_out/choose_settings.png]
                                   [--quick]
"""

import argparse
import logging
import os
import warnings

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from seds_casadi import SEDS, ConvergenceWarning, DemoSearchCV  # noqa: E402
from seds_casadi.app.plot_ds import plot_streamlines  # noqa: E402
from seds_casadi.core.datasets import load_lasa  # noqa: E402
from seds_casadi.core.search import METRICS  # noqa: E402

ap = argparse.ArgumentParser()
ap.add_argument("--shape", default="Leaf_1", help="a LASA shape [Leaf_1]")
ap.add_argument("--out", default="examples_out/choose_settings.png",
                help="the figure's file; its folder is made [examples_out/choose_settings.png]")
ap.add_argument("--quick", action="store_true", help="smaller data and fewer folds, for CI")
args = ap.parse_args()
os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
logging.basicConfig(format="%(message)s")
logging.getLogger("seds_casadi.core.search").setLevel(logging.INFO)  # a line per fold

demos = load_lasa(args.shape, n_samples=40 if args.quick else 150)
grid = {"objective": ["mse", "direction"], "lyapunov": ["identity", "learned"]}
search = DemoSearchCV(SEDS(n_components=3 if args.quick else 4, random_state=0,
                           gain_limit=10.0, max_iter=100 if args.quick else 500),
                      grid, cv=3 if args.quick else "loo", verbose=1)
with warnings.catch_warnings():
    warnings.simplefilter("ignore", ConvergenceWarning)
    search.fit(demos)
print(search.table())
model = search.model_
print(f"chosen: {search.best_params_}; certified: {bool(model.certificate)}")

res = search.cv_results_
labels = [f"{p['objective']}\nP = {'I' if p['lyapunov'] == 'identity' else 'learned'}"
          for p in res["params"]]
fig, axs = plt.subplots(1, 2, figsize=(12, 5), gridspec_kw={"width_ratios": [1.25, 1]})
width = 0.8 / len(METRICS)
for j, m in enumerate(METRICS):
    v = np.asarray(res[f"mean_{m}"])
    ratio = v / np.min(v[np.isfinite(v)])
    axs[0].bar(np.arange(len(v)) + (j - 1) * width, ratio, width,
               label={"rmse": "velocity RMSE", "e_dot": "e_dot", "dtw": "DTW"}[m])
best = search.best_index_
axs[0].axvspan(best - 0.45, best + 0.45, color="0.9", zorder=-1, label="chosen")
axs[0].set_xticks(range(len(labels)), labels)
axs[0].set_ylabel("held-out mean / best candidate's")
axs[0].set_title(f"LASA {args.shape}: {search.n_splits_} folds, demonstrations held out")
axs[0].legend()
starts = [p[0] for p in demos.positions]
plot_streamlines(model, demos, model.rollout(starts, dt=0.05, tol=1.0, warn=False), ax=axs[1],
                 title=f"chosen: {labels[best].replace(chr(10), ', ')}", unit="mm")
fig.tight_layout()
fig.savefig(args.out, dpi=110, bbox_inches="tight")
print(f"wrote {args.out}")
