"""Model selection with scikit-learn: GridSearchCV picks K for SEDS (folds by demonstration) and
for the hitting-parameter GMR; the figure shows the cross-validated R^2 against K and the
streamlines of the chosen SEDS model.

python examples/model_selection.py [--out examples_out/model_selection.png] [--quick]
"""

import argparse
import os
import warnings

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from sklearn.model_selection import GridSearchCV, GroupKFold, KFold  # noqa: E402

from seds_casadi import SEDS, ConvergenceWarning  # noqa: E402
from seds_casadi.app.plot_ds import plot_streamlines  # noqa: E402
from seds_casadi.core.datasets import load_lasa  # noqa: E402
from seds_casadi.minigolf.parameters import GMRModel  # noqa: E402

ap = argparse.ArgumentParser()
ap.add_argument("--out", default="examples_out/model_selection.png",
                help="the figure's file; its folder is made [examples_out/model_selection.png]")
ap.add_argument("--quick", action="store_true", help="smaller data for CI")
args = ap.parse_args()
os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)

# SEDS: samples of 7 LASA demonstrations; a fold holds out whole demonstrations
demos = load_lasa("Sshape", n_samples=25 if args.quick else 60)
X, Xdot, _, groups = demos.stacked()
Ks = [1, 2, 3] if args.quick else [1, 2, 3, 4, 5, 6]
search = GridSearchCV(SEDS(objective="mse", random_state=0, max_iter=100 if args.quick else 300),
                      {"n_components": Ks}, cv=GroupKFold(n_splits=3 if args.quick else 7))
with warnings.catch_warnings():
    warnings.simplefilter("ignore", ConvergenceWarning)
    search.fit(X + demos.target, Xdot, groups=groups, target=demos.target)
seds_scores = search.cv_results_["mean_test_score"]
best = search.best_estimator_.model_
print(f"SEDS: best K = {search.best_params_['n_components']} "
      f"(held-out R^2 {search.best_score_:.3f}); certified: {bool(best.certificate)}")

# hitting parameters: a two-branch map of the situation, as on a field with two strategies
rng = np.random.default_rng(0)
S = np.column_stack([np.full(80, 2.4), rng.uniform(-0.5, 0.5, 80)])
Y = np.column_stack([np.where(S[:, 1] > 0, 4.0, -4.0) + 6 * S[:, 1],
                     1.0 + 0.3 * np.abs(S[:, 1])])
gmr = GridSearchCV(GMRModel(random_state=0), {"n_components": [1, 2, 3, 4]},
                   cv=KFold(4, shuffle=True, random_state=0)).fit(S, Y)
gmr_scores = gmr.cv_results_["mean_test_score"]
print(f"GMR: best K = {gmr.best_params_['n_components']} (held-out R^2 {gmr.best_score_:.3f})")

fig, axs = plt.subplots(1, 3, figsize=(13, 4))
axs[0].plot(Ks, seds_scores, "o-", label="SEDS (mse), Sshape")
axs[0].plot([1, 2, 3, 4], gmr_scores, "s-", label="GMR, hitting parameters")
axs[0].set_xlabel("number of Gaussians K")
axs[0].set_ylabel("held-out R$^2$ (mean over folds)")
axs[0].set_title("GridSearchCV over K")
axs[0].legend()
starts = [p[0] for p in demos.positions]
plot_streamlines(best, demos, best.rollout(starts, dt=0.05, tol=1.0), ax=axs[1],
                 title=f"LASA Sshape, chosen K = {best.n_components}", unit="mm")
St = np.column_stack([np.full(200, 2.4), np.linspace(-0.5, 0.5, 200)])
axs[2].plot(S[:, 1], Y[:, 0], ".", color="0.5", label="training shots")
axs[2].plot(St[:, 1], gmr.predict(St)[:, 0], "-", label=f"GMR, K = {gmr.best_params_['n_components']}")
axs[2].set_xlabel("hole sideways from the ball, s_y [m]")
axs[2].set_ylabel("hitting angle alpha [deg]")
axs[2].set_title("hitting-parameter GMR, chosen K")
axs[2].legend()
fig.tight_layout()
fig.savefig(args.out, dpi=110, bbox_inches="tight")
print(f"wrote {args.out}")
