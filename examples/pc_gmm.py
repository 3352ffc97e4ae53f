"""A physically-consistent GMM, fixed, under a learned Lyapunov function (LPV-DS's split inside
the SEDS problem) against SEDS's joint fit, on a LASA shape under the published protocol
(ds-opt: demos 1-4 train, 5-7 test, every 2nd sample).

Three models: SEDS (joint EM start, GMM and dynamics optimised together, P = I); the same with
a learned P; and ``init="pc", gmm="fixed"`` with a learned P, whose components come from the
clustering of samples that are close *and* move the same way (PC-GMM's similarity), kept fixed
while IPOPT fits the dynamics and P. Each panel: the components' 2-sigma ellipses, the
streamlines, the test demonstrations and their reproductions by the protocol's rule (Euler at
0.01 s from the 20th point), and the test metrics in the title.

python examples/pc_gmm.py [--shape JShape] [-K 6] [--out examples_out/pc_gmm.png] [--quick]
"""

import argparse
import os
import warnings

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from seds_casadi import SEDS  # noqa: E402
from seds_casadi.app.lasa import dsopt_scores, dsopt_sets  # noqa: E402

ap = argparse.ArgumentParser()
ap.add_argument("--shape", default="JShape", help="a LASA shape [JShape]")
ap.add_argument("-K", type=int, default=6, help="components [6]")
ap.add_argument("--out", default="examples_out/pc_gmm.png",
                help="the figure's file; its folder is made [examples_out/pc_gmm.png]")
ap.add_argument("--quick", action="store_true", help="fewer IPOPT iterations, for CI")
args = ap.parse_args()
os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)

sets = dsopt_sets(args.shape)
train, test = sets["train"], sets["test"]
max_iter = 60 if args.quick else 1000
variants = [
    ("SEDS: joint EM, joint fit, P = I", {}),
    ("joint EM, joint fit, learned P", {"lyapunov": "learned", "gain_limit": 10.0}),
    ("PC-GMM fixed, learned P", {"lyapunov": "learned", "gain_limit": 10.0, "init": "pc",
                                 "gmm": "fixed"}),
]
allx = np.concatenate(train.positions + test.positions)
lo, hi = allx.min(0), allx.max(0)
pad = 0.15 * (hi - lo)
GX, GY = np.meshgrid(np.linspace(lo[0] - pad[0], hi[0] + pad[0], 70),
                     np.linspace(lo[1] - pad[1], hi[1] + pad[1], 70))
pts = np.c_[GX.ravel(), GY.ravel()]
t = np.linspace(0, 2 * np.pi, 60)
circle = np.c_[np.cos(t), np.sin(t)]

fig, axes = plt.subplots(1, 3, figsize=(16, 5.2), constrained_layout=True)
for ax, (name, opts) in zip(axes, variants):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = SEDS(args.K, objective="mse", random_state=0, max_iter=max_iter,
                     **opts).fit(train.demonstrations()).model_
    rmse, e_dot, dtwd, paths = dsopt_scores(model.predict, test)
    print(f"{name:<36} RMSE {rmse:6.2f} mm/s  e_dot {e_dot:.3f}  DTWD {dtwd:8.0f} mm  "
          f"fit {model.fit_info['seconds']:.1f} s  certified {bool(model.certificate)}")
    F = model.predict(pts)
    ax.streamplot(GX, GY, F[:, 0].reshape(GX.shape), F[:, 1].reshape(GX.shape), color="0.65",
                  density=1.2, linewidth=0.7, arrowsize=0.8)
    for k in range(model.n_components):
        ev, V = np.linalg.eigh(model.covariances[k, :2, :2])
        ell = model.means[k, :2] + 2 * (circle * np.sqrt(np.maximum(ev, 0))) @ V.T
        ax.fill(ell[:, 0], ell[:, 1], color=f"C{k % 10}", alpha=0.18, lw=0)
        ax.plot(ell[:, 0], ell[:, 1], color=f"C{k % 10}", lw=1.0)
    for p in train.positions:
        ax.plot(p[:, 0], p[:, 1], color="tab:red", lw=1.4)
    for p in test.positions:
        ax.plot(p[:, 0], p[:, 1], color="tab:orange", lw=1.2, ls="--")
    for n in range(paths.shape[1]):
        ax.plot(paths[:, n, 0], paths[:, n, 1], color="tab:blue", lw=1.4)
    ax.plot(*model.target, "k*", ms=10)
    ax.set_title(f"{args.shape}, K = {args.K}: {name}\ntest RMSE {rmse:.2f} mm/s, e_dot "
                 f"{e_dot:.3f}, DTWD {dtwd:,.0f} mm", fontsize=9)
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlim(GX.min(), GX.max())
    ax.set_ylim(GY.min(), GY.max())
axes[0].plot([], [], color="tab:red", label="training demos (1-4)")
axes[0].plot([], [], color="tab:orange", ls="--", label="test demos (5-7)")
axes[0].plot([], [], color="tab:blue", label="reproductions from the test starts")
axes[0].fill([], [], color="C0", alpha=0.3, label="components (2 sigma)")
axes[0].legend(fontsize=7, loc="best")
fig.savefig(args.out, dpi=110)
print(f"wrote {args.out}")
