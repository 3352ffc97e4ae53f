"""The direction objective (Eq. 9) at the demonstrated speeds, on 3-D data of your own kind.

Eq. 9 fixes only the directions of the learned DS; its speed comes from a strength factor v(x)
learned by GMR (Eq. 12) that moves the model along its certified streamlines at the
demonstrated speeds (``speed_calibration="strength"``, the default). This example makes 3-D
demonstrations of a helical approach that speeds up and slows down along the way, fits both
calibrations, prints the speed ratio along the demonstrations and the time each reproduction
takes to reach the target, and draws speed against time.

python examples/direction_speeds.py [--out examples_out/direction_speeds.png] [--quick]
"""

import argparse
import os
import warnings

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from seds_casadi import SEDS, ConvergenceWarning, Demonstrations  # noqa: E402

ap = argparse.ArgumentParser()
ap.add_argument("--out", default="examples_out/direction_speeds.png",
                help="the figure's file; its folder is made [examples_out/direction_speeds.png]")
ap.add_argument("--quick", action="store_true", help="smaller data for CI")
args = ap.parse_args()
os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)

# five demonstrations: a helix shrinking onto the target, 4 s each, with a speed bump midway
rng = np.random.default_rng(0)
n, duration = (60 if args.quick else 200), 4.0
t = np.linspace(0.0, 1.0, n)
s = t + 0.15 * np.sin(2 * np.pi * t) / (2 * np.pi)  # progress: slower, faster, slower
demos_xyz = []
for _ in range(5):
    r0, phase, z0 = rng.uniform(0.18, 0.22), rng.uniform(-0.3, 0.3), rng.uniform(0.25, 0.3)
    a = phase + 3 * np.pi * s
    r = r0 * (1 - s)
    demos_xyz.append(np.column_stack([r * np.cos(a), r * np.sin(a), z0 * (1 - s) ** 2]))
demos = Demonstrations(demos_xyz, dt=duration / (n - 1), target=np.zeros(3))

fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), sharey=True)
for ax, how in zip(axes, ("strength", "median")):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        model = SEDS(3 if args.quick else 4, objective="direction", random_state=0,
                     speed_calibration=how).fit(demos).model_
    X = np.concatenate(demos.positions)
    V = np.concatenate(demos.velocities)
    nv = np.linalg.norm(V, axis=1)
    ratio = np.linalg.norm(model.predict(X[nv > 0]), axis=1) / nv[nv > 0]
    dt = duration / 400
    starts = np.array([p[0] for p in demos.positions])
    paths, info = model.rollout(starts, dt=dt, max_steps=1200, tol=0.01 * 0.4,
                                return_info=True, warn=False)
    arrive = [f"{k * dt:.1f} s" if ok else "no" for k, ok in zip(info["steps"],
                                                                  info["converged"])]
    print(f"{how:>8}: speed ratio model/demo p10 / median / p90 = "
          f"{np.percentile(ratio, 10):.2f} / {np.median(ratio):.2f} / "
          f"{np.percentile(ratio, 90):.2f}; reaches the target (1 % of 0.4 m) after "
          f"{', '.join(arrive)} (demos: {duration:.0f} s)")
    for i, (p, v) in enumerate(zip(demos.positions, demos.velocities)):
        tt = np.linspace(0.0, duration, len(p))
        ax.plot(tt, np.linalg.norm(v, axis=1), color="tab:red", lw=1.2,
                label="demonstrations" if i == 0 else None)
        path = paths[i]
        ax.plot(dt * np.arange(len(path)), np.linalg.norm(model.predict(path), axis=1),
                color="tab:blue", ls="--", lw=1.0, label="reproductions" if i == 0 else None)
    ax.set_title(f"speed_calibration={how!r}: {int(info['converged'].sum())}/5 arrive "
                 "within 3x the duration", fontsize=9)
    ax.set_xlabel("time [s]")
    ax.set_xlim(0, 1.6 * duration)
    ax.legend(fontsize=8)
axes[0].set_ylabel("speed [m/s]")
fig.tight_layout()
fig.savefig(args.out, dpi=110)
print(f"wrote {args.out}")
