"""Table 1 under the paper's protocol and its variants: how the rows move with the choices the
paper leaves open (issue 33).

Learns the hitting motion, lets the teacher collect its data sets and measures their sinking
sets once, then runs :func:`seds_casadi.minigolf.table1.run_table1` for each variant and
prints, per variant, the success rates beside the paper's, the rows within 0.1 and the paper's
conclusions:

* ``grid``: the protocol before issue 33 (the teacher's shots as they are, random points over
  the whole range, GPR's prior mean the training mean, the field files as they are);
* ``paper``: the default (noise anywhere in the sinking set, centred range 0.6, zero-mean GPR,
  the fields as the paper's simulator modelled them: ``simulated_field``);
* ``rough surface``: ``paper`` on the field files as they are (the rough flat field with its
  bumps and friction variation);
* ``GPR mean``: ``paper`` with GPR's prior mean the training outputs' mean;
* ``noise 0.5`` / ``noise 0``: the examples drawn from the middle half of each sinking
  interval / its middle (no noise);
* ``centre 0.7`` / ``centre 1``: the random training points from a wider centred range / the
  whole range;
* ``minimal speed``: arctan's examples at the slowest gain of its sinking set (the slowest
  that sinks over 1 deg: "we chose hitting parameters so as to minimize the hitting speed"
  read literally, without the teacher's 3 % margin), the angle anywhere in its interval there.

Besides the success rates it prints the angle's RMSE of the arctan rows.

python benchmarks/table1_sensitivity.py [--repetitions 30] [--workers 1] [--only VARIANT ...]
"""

import argparse
import time

from seds_casadi.app.executors import open_executor
from seds_casadi.minigolf import Stroke, collect_dataset
from seds_casadi.minigolf.fields import load_field
from seds_casadi.minigolf.sinking import SinkingSet, sinking_set
from seds_casadi.minigolf.table1 import (
    PAPER_TABLE1,
    TABLE1_FIELDS,
    paper_conclusions,
    rows_within,
    run_table1,
    simulated_field,
)
from seds_casadi.minigolf.teacher import Teacher
from seds_casadi.motion.hitting import HittingMotionLearner
from seds_casadi.motion.putting_demos import load_hitting_demos

VARIANTS = {
    "grid": {"protocol": "grid"},
    "paper": {},
    "rough surface": {},
    "GPR mean": {"gpr_prior_mean": "data"},
    "noise 0.5": {"noise_spread": 0.5},
    "noise 0": {"noise_spread": 0.0},
    "centre 0.7": {"centre_fraction": 0.7},
    "centre 1": {"centre_fraction": 1.0},
    "minimal speed": {},
}

ap = argparse.ArgumentParser()
ap.add_argument("--repetitions", type=int, default=30)
ap.add_argument("--workers", type=int, default=1)
ap.add_argument("--only", nargs="+", choices=list(VARIANTS), help="run these variants only")
args = ap.parse_args()
if args.only:
    VARIANTS = {k: v for k, v in VARIANTS.items() if k in args.only}

stroke = Stroke.from_motion(HittingMotionLearner(n_components=3).fit(load_hitting_demos())
                            .motion_)
# the field files as they are ("grid", "rough surface") and as the paper's simulator
# modelled them (every other variant); only a rough surface differs
data = {"files": ({}, {}), "simulated": ({}, {})}
for name in TABLE1_FIELDS:
    loaded = load_field(name)
    for kind, f in (("files", loaded), ("simulated", simulated_field(loaded))):
        if kind == "simulated" and f is loaded:
            data[kind][0][name], data[kind][1][name] = (data["files"][0][name],
                                                        data["files"][1][name])
            continue
        ds = collect_dataset(f, stroke)
        data[kind][0][name] = (f, ds)
        data[kind][1][name] = sinking_set(Teacher(f, stroke), ds)

results = {}
with open_executor(args.workers) as ex:
    for label, kw in VARIANTS.items():
        t0 = time.perf_counter()
        datasets, sinking = data["files" if label in ("grid", "rough surface")
                                 else "simulated"]
        if label == "minimal speed":
            # the slowest gain of each sinking set measured at several gains
            sinking = {n: (SinkingSet(k.gains[:, :1], k.lower[:, :1], k.upper[:, :1], False)
                           if not k.fixed_speed else k) for n, k in sinking.items()}
        means, _ = run_table1(datasets, args.repetitions, 0, ex, sinking=sinking, **kw)
        results[label] = means
        print(f"{label}: {time.perf_counter() - t0:.0f} s", flush=True)

first = next(iter(VARIANTS))
keys = [(r.field, r.training, r.model) for r in results[first]]
print(f"\nsuccess over {args.repetitions} repetitions (paper's in the last column)")
print(f"{'field':<12} {'training':<18} {'model':<8} "
      + " ".join(f"{v:>10}" for v in VARIANTS) + f" {'paper':>6}")
for key in keys:
    row = {v: next(r for r in results[v] if (r.field, r.training, r.model) == key)
           for v in VARIANTS}
    print(f"{key[0]:<12} {key[1]:<18} {key[2]:<8} "
          + " ".join(f"{row[v].success_rate:>10.2f}" for v in VARIANTS)
          + f" {PAPER_TABLE1[key][2]:>6.2f}")
print(f"{'within 0.1':<40} "
      + " ".join(f"{'{}/{}'.format(*rows_within(results[v])):>10}" for v in VARIANTS))
for c in paper_conclusions(results[first]):
    print(f"{c:<40} " + " ".join(
        f"{('holds' if paper_conclusions(results[v])[c] else 'no'):>10}" for v in VARIANTS))
print("\nangle RMSE [deg] of the arctan rows")
for key in [k for k in keys if k[0] == "arctan"]:
    row = {v: next(r for r in results[v] if (r.field, r.training, r.model) == key)
           for v in VARIANTS}
    print(f"{key[0]:<12} {key[1]:<18} {key[2]:<8} "
          + " ".join(f"{row[v].rmse_angle:>10.2f}" for v in VARIANTS)
          + f" {PAPER_TABLE1[key][0]:>6.2f}")
