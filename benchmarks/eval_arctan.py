"""Why the arctan rows of Table 1 were far from the paper's: measurements (issue 15).

For the arctan field (or a variant of its geometry) and the teacher's data set on it, prints

* the geometry: distance from the ball region's centre to the hole, the steepest slope, the
  range of the taught hitting angles and gains;
* the **width of the success region at the teacher's shots**: the interval of angles that sink
  at the taught gain, and of gains at the taught angle (median and 10th percentile over the
  56 situations);
* the **teacher's noise**: the RMS change of the taught angles and gains when the teacher
  searches a grid twice as fine (``--noise``);
* the **learners' errors against those widths**: GPR trained on the equally spaced half (the
  checkerboard of Table 1's "28 equally spaced"), its angle errors on the other half, and the
  share of those situations where its (alpha, kappa) still sinks;
* Table 1's arctan rows (``--repetitions``, default 20).

python benchmarks/eval_arctan.py                       # the shipped arctan field
python benchmarks/eval_arctan.py --hole-x 2.4 --length 3.0 --noise
                                                       # the field as it was before issue 15

It uses only APIs that the code before issue 15 had too (``collect_dataset`` with keywords,
``success_map``, ``run_table1``), so the same script measures the earlier teacher when run
against that code.
"""

import argparse
import copy
import time

import numpy as np

from seds_casadi.minigolf import Stroke, collect_dataset, success_map
from seds_casadi.minigolf.ball import simulate_shots
from seds_casadi.minigolf.fields import Field, load_field
from seds_casadi.minigolf.parameters import make_model
from seds_casadi.minigolf.table1 import format_table1, run_table1, training_indices
from seds_casadi.motion.hitting import HittingMotionLearner
from seds_casadi.motion.putting_demos import load_hitting_demos

ap = argparse.ArgumentParser()
ap.add_argument("--hole-x", type=float, default=None, help="move the hole to this x [m]")
ap.add_argument("--length", type=float, default=None, help="the field's far edge x [m]")
ap.add_argument("--height", type=float, default=None, help="the arctan's height [m]")
ap.add_argument("--steepness", type=float, default=None, help="the arctan's steepness [1/m]")
ap.add_argument("--repetitions", type=int, default=20)
ap.add_argument("--noise", action="store_true", help="teach again on a twice finer grid")
args = ap.parse_args()

spec = copy.deepcopy(load_field("arctan").spec)
if args.hole_x is not None:
    spec["hole"]["x"] = args.hole_x
    if "situations" in spec:
        spec["situations"]["hole"] = {"fixed": [args.hole_x, spec["hole"]["y"]]}
if args.length is not None:
    spec["bounds"][1] = args.length
for key in ("height", "steepness"):
    if getattr(args, key) is not None:
        spec["surface"][key] = getattr(args, key)
field = Field.from_dict(spec, source="arctan")
stroke = Stroke.from_motion(HittingMotionLearner(n_components=3).fit(load_hitting_demos()).motion_)

t0 = time.perf_counter()
ds = collect_dataset(field, stroke)
print(f"teacher: {len(ds)} shots ({ds.strategy}, dropped {ds.dropped}) in "
      f"{time.perf_counter() - t0:.1f} s")
centre = np.array([np.mean(field.ball_region[:2]), np.mean(field.ball_region[2:])])
y = np.linspace(field.bounds[2], field.bounds[3], 2001)
slope = np.abs(field.surface.gradient(np.column_stack([np.full_like(y, 1.0), y]))[:, 1]).max()
A = np.rad2deg(ds.alpha)
print(f"geometry: hole {field.hole.tolist()}, {np.linalg.norm(field.hole - centre):.2f} m from "
      f"the ball region's centre; field x {field.bounds[0]}..{field.bounds[1]}; steepest slope "
      f"{np.degrees(np.arctan(slope)):.1f} deg; taught alpha {A.min():.1f}..{A.max():.1f} deg, "
      f"kappa {ds.kappa.min():.2f}..{ds.kappa.max():.2f}")

# width of the success region at the teacher's shots
wa, wk, ha = [], [], []
for i in range(len(ds)):
    da = np.linspace(-8.0, 8.0, 801)
    row = success_map(field, stroke, ds.ball[i], ds.hole[i], ds.alpha[i] + np.deg2rad(da),
                      [ds.kappa[i]], banks=False)[0]
    dk = np.linspace(-0.3, 0.3, 601)
    col = success_map(field, stroke, ds.ball[i], ds.hole[i], [ds.alpha[i]], ds.kappa[i] + dk,
                      banks=False)[:, 0]

    def run(mask, c):
        if not mask[c]:
            return 0, 0
        lo = c - np.argmin(mask[c::-1]) if not mask[:c + 1].all() else 0
        hi = c + np.argmin(mask[c:]) if not mask[c:].all() else len(mask)
        return lo, hi

    lo, hi = run(row, 400)
    wa.append((hi - lo) * 0.02)
    ha.append(min(400 - lo, hi - 400) * 0.02)  # distance to the nearer edge [deg]
    lo, hi = run(col, 300)
    wk.append((hi - lo) * 0.001)
wa, wk, ha = map(np.array, (wa, wk, ha))
print(f"success region at the teacher's shots: alpha interval median {np.median(wa):.2f} deg "
      f"(10th percentile {np.percentile(wa, 10):.2f}), nearer edge median {np.median(ha):.2f} "
      f"deg; kappa interval median {np.median(wk):.3f} (10th percentile "
      f"{np.percentile(wk, 10):.3f})")

if args.noise:
    t0 = time.perf_counter()
    fine = collect_dataset(field, stroke, resolution=(321, 129))
    same = len(fine) == len(ds) and np.allclose(fine.ball, ds.ball)
    if same:
        print(f"teacher's noise (grid twice as fine, {time.perf_counter() - t0:.0f} s): alpha "
              f"RMS {np.sqrt(np.mean((np.rad2deg(fine.alpha) - A) ** 2)):.2f} deg, max "
              f"{np.abs(np.rad2deg(fine.alpha) - A).max():.2f}; kappa RMS "
              f"{np.sqrt(np.mean((fine.kappa - ds.kappa) ** 2)):.4f}")

# the learners' errors against the widths: GPR on the checkerboard, tested on the other half
S, Y = ds.situations, np.column_stack([A, ds.kappa])
idx = training_indices(S, 28, "spaced", np.random.default_rng(0))
test = np.setdiff1d(np.arange(len(ds)), idx)
pred = make_model("gpr").fit(S[idx], Y[idx]).predict(S[test])
err = np.abs(pred[:, 0] - Y[test, 0])
V = stroke.launch_velocity(np.deg2rad(pred[:, 0]), pred[:, 1])
sunk = simulate_shots(field, ds.ball[test], V, hole=ds.hole[test]).sunk
print(f"GPR on the 28 equally spaced: angle error median {np.median(err):.2f} deg, RMS "
      f"{np.sqrt(np.mean(err ** 2)):.2f}; inside the nearer edge {np.mean(err < ha[test]):.0%};"
      f" held-out situations sunk {sunk.mean():.0%}")

means, _ = run_table1({"arctan": (field, ds)}, args.repetitions, 0, protocol="grid")
print(format_table1(means))
