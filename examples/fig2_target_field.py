"""Paper Fig. 2: streamlines of a 2-D SEDS model f against its target field h = f/||f|| (Eq. 8).

Both have exactly the same streamlines, but h keeps unit speed up to the target (colour: speed).

python examples/fig2_target_field.py [--out examples_out/fig2.png] [--quick]
"""

import argparse
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from seds_casadi import SEDS  # noqa: E402
from seds_casadi.core.datasets import load_lasa
from seds_casadi.motion import TargetField

ap = argparse.ArgumentParser()
ap.add_argument("--out", default="examples_out/fig2.png",
                help="the figure's file; its folder is made [examples_out/fig2.png]")
ap.add_argument("--quick", action="store_true", help="smaller data for CI")
args = ap.parse_args()
os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)

demos = load_lasa("Angle", n_samples=30 if args.quick else 100)
ds = SEDS(n_components=2, objective="direction", random_state=0).fit(demos).model_
h = TargetField(ds, approach=np.mean([v[-1] for v in demos.velocities], axis=0))

P = np.concatenate(demos.positions)
lo, hi = P.min(0) - 5, P.max(0) + 5
gx, gy = np.meshgrid(np.linspace(lo[0], hi[0], 70), np.linspace(lo[1], hi[1], 70))
G = np.column_stack([gx.ravel(), gy.ravel()])
fig, axes = plt.subplots(1, 2, figsize=(10, 4.5))
for ax, (name, F) in zip(axes, (("SEDS model f(x)", ds.predict(G)), ("target field h(x)", h(G)))):
    speed = np.linalg.norm(F, axis=1).reshape(gx.shape)
    ax.streamplot(gx, gy, F[:, 0].reshape(gx.shape), F[:, 1].reshape(gx.shape), color=speed,
                  cmap="viridis", density=1.3, linewidth=0.8)
    for k, p in enumerate(demos.positions):
        ax.plot(p[:, 0], p[:, 1], ".", color="tab:red", ms=2,
                label="LASA Angle demonstrations" if k == 0 else None)
    ax.plot(*ds.target, "k*", ms=12, ls="", label="target")
    unit = "mm/s" if name.startswith("SEDS") else "dimensionless"
    ax.set_title(f"{name}: speed {speed.min():.2g} .. {speed.max():.2g} ({unit}; colour)",
                 fontsize=9)
    ax.set_aspect("equal")
    ax.set_xlabel("x1 [mm]")
    ax.set_ylabel("x2 [mm]")
    ax.legend(fontsize=7, loc="lower left")
fig.suptitle("Fig. 2: SEDS streamlines vs the target field (same streamlines, unit speed)")
fig.savefig(args.out, dpi=110, bbox_inches="tight")
print(f"wrote {args.out}")
