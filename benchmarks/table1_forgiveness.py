"""Table 1's rough flat and double hill rows if our fields forgave as little as the paper's
(issue 33): the argument for the rows the paper protocol does not match, measured.

The paper's own pairs of angle RMSE and success (Table 1; the equally spaced rows and GMR's,
whose errors are spread rather than the extrapolation's few large ones) put the edge of its
successful angle interval about 0.45 deg from the learned angle on the rough flat field and
0.26 deg on the double hill, if the errors are Gaussian with that RMSE: P(|e| <= w) = success
gives w = RMSE * sqrt(2) * erfinv(success), see :func:`paper_half_widths`. Ours are 1.2 and
0.7 deg at the median (:func:`~seds_casadi.minigolf.sinking.sinking_set`): about 0.37 of ours
on both fields.

This script measures, along each field's slider (the hole at 201 positions), the successful
angle interval at the teacher's fixed speed (the run holding the teacher's angle, interpolated
between its 20 shots), and then runs the ``"paper"`` protocol of
:mod:`seds_casadi.minigolf.table1` with every interval narrowed about its middle by a factor
``f``: the examples are drawn from the narrowed intervals (Eq. 15's noise scaled with them) and
a test situation counts as sunk when the prediction lies in its narrowed interval. ``f = 1`` is
the protocol itself with success read from the intervals instead of the ball model (a check:
the two agree within a few hundredths). The other factors ask what the protocol gives on fields
that forgive as the paper's did; they are not a reproduction (the ball model is not played).

``--plane`` runs the rough flat field with its surface replaced by a plane (no bumps, no
friction variation; the same slider, hole, speed and walls: the field as the paper's simulator
modelled it, :func:`~seds_casadi.minigolf.table1.simulated_field`): a field whose angle is a
smooth function of the situation, to separate the intervals' width from the angle's structure.

python benchmarks/table1_forgiveness.py [--repetitions 100] [--factors 1 0.5 0.37 0.25]
                                        [--plane]
"""

import argparse
import time
import zlib

import numpy as np
from scipy.special import erfinv

from seds_casadi.minigolf import Stroke, collect_dataset
from seds_casadi.minigolf.fields import load_field
from seds_casadi.minigolf.parameters import make_model
from seds_casadi.minigolf.sinking import sinking_set
from seds_casadi.minigolf.table1 import (
    GPR_PRIOR_MEAN,
    N_COMPONENTS,
    N_TEST_SITUATIONS,
    PAPER_TABLE1,
    PAPER_TRAINING_SETS,
    run_table1,
    simulated_field,
    training_indices,
)
from seds_casadi.minigolf.teacher import Teacher, true_runs
from seds_casadi.motion.hitting import HittingMotionLearner
from seds_casadi.motion.putting_demos import load_hitting_demos

FIELDS = ("rough_flat", "double_hill")
N_POSITIONS = 201


def paper_half_widths() -> dict:
    """Per field, the half-width w [deg] of the paper's successful interval implied by each
    of its rows with spread errors (the equally spaced rows and GMR's), if the errors are
    Gaussian with the row's RMSE: success = P(|e| <= w), w = RMSE sqrt(2) erfinv(success)."""
    out = {}
    for (field, training, model), (rmse, _, success, _) in PAPER_TABLE1.items():
        if field in FIELDS and (model == "gmr" or "spaced" in training):
            out.setdefault(field, []).append(rmse * np.sqrt(2) * erfinv(success))
    return out


def slider_windows(teacher: Teacher, ds, n: int = N_POSITIONS, step_deg: float = 0.02,
                   half_span_deg: float = 15.0):
    """Holes at ``n`` positions along the data set's slider and, at each, the successful
    angle interval [deg] at the fixed speed: the run holding the teacher's angle (linearly
    interpolated between its shots), else the nearest run."""
    t = np.linspace(0.0, 1.0, n)
    holes = ds.hole[0] + t[:, None] * (ds.hole[-1] - ds.hole[0])
    along = np.linalg.norm(ds.hole - ds.hole[0], axis=1)
    guide = np.interp(t * along[-1], along, ds.alpha)
    offsets = np.deg2rad(np.arange(-half_span_deg, half_span_deg + 0.5 * step_deg, step_deg))
    lower, upper = np.full(n, np.nan), np.full(n, np.nan)
    for i in range(n):
        scan = guide[i] + offsets
        runs = true_runs(teacher.map(ds.ball[0], holes[i], scan, [ds.kappa[0]])[0])
        if not runs:
            continue
        dist = [0.0 if scan[s] <= guide[i] <= scan[e - 1]
                else min(abs(scan[s] - guide[i]), abs(scan[e - 1] - guide[i])) for s, e in runs]
        s, e = runs[int(np.argmin(dist))]
        lower[i], upper[i] = np.rad2deg(scan[s]), np.rad2deg(scan[e - 1])
    return holes, lower, upper


def widths_at_gains(teacher: Teacher, ds, gains, every: int = 2, step_deg: float = 0.02,
                    half_span_deg: float = 20.0) -> np.ndarray:
    """Width [deg] of the successful angle interval nearest the teacher's angle (0: none
    sinks) at every ``every``-th of its situations, at each of ``gains``: shape
    (len(gains), m). The paper fixes the speed without saying at what; a faster hit narrows
    the hole's capture."""
    scan = np.deg2rad(np.arange(-half_span_deg, half_span_deg, step_deg))
    centre = int(np.argmin(np.abs(scan)))
    out = []
    for k in gains:
        row = []
        for i in range(0, len(ds), every):
            runs = true_runs(teacher.map(ds.ball[i], ds.hole[i], ds.alpha[i] + scan, [k])[0])
            gap = [0 if s <= centre < e else min(abs(s - centre), abs(e - 1 - centre))
                   for s, e in runs]
            row.append(step_deg * (np.subtract(*runs[int(np.argmin(gap))][::-1]) if runs
                                   else 0))
        out.append(row)
    return np.array(out)


def run(field_name, ds, sink, holes, lower, upper, factor, repetitions, seed=0):
    """The ``"paper"`` protocol with intervals narrowed by ``factor`` (module docstring):
    {(training, model): mean success}."""
    S = ds.situations
    test_s = holes - ds.ball[0]
    mid, half = 0.5 * (lower + upper), 0.5 * factor * (upper - lower)
    ok = np.isfinite(mid)
    out = {}
    for ti, (label, size, kind) in enumerate(PAPER_TRAINING_SETS[1]):
        for rep in range(repetitions):
            rng = np.random.default_rng([seed, zlib.crc32(field_name.encode()), ti, rep])
            Y = sink.draw(rng, factor)[:, :1]
            idx = training_indices(S, size, kind, rng)
            tests = rng.choice(np.flatnonzero(ok), N_TEST_SITUATIONS)
            for name in ("gpr", "gmr"):
                kw = ({"prior_mean": GPR_PRIOR_MEAN["paper"]} if name == "gpr"
                      else {"n_components": N_COMPONENTS[1]})
                model = make_model(name, random_state=rep, **kw).fit(S[idx], Y[idx])
                pred = model.predict(test_s[tests])[:, 0]
                sunk = np.abs(pred - mid[tests]) <= half[tests]
                out.setdefault((label, name), []).append(sunk.mean())
    return {k: float(np.mean(v)) for k, v in out.items()}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repetitions", type=int, default=100)
    ap.add_argument("--factors", type=float, nargs="+", default=[1.0, 0.5, 0.37, 0.25])
    ap.add_argument("--plane", action="store_true",
                    help="the rough flat field only, its surface a plane")
    args = ap.parse_args()
    fields = ("rough_flat",) if args.plane else FIELDS
    t0 = time.perf_counter()
    stroke = Stroke.from_motion(HittingMotionLearner(n_components=3).fit(load_hitting_demos())
                                .motion_)
    implied = paper_half_widths()
    results, simulated = {}, {}
    for name in fields:
        f = load_field(name)
        if args.plane:
            f = simulated_field(f)  # the rough surface's plane
        teacher = Teacher(f, stroke)
        ds = collect_dataset(f, stroke)
        sink = sinking_set(teacher, ds)
        holes, lower, upper = slider_windows(teacher, ds)
        w = 0.5 * (upper - lower)
        print(f"{name}: half-widths along the slider {np.nanmedian(w):.2f} deg median "
              f"({np.nanmin(w):.2f}-{np.nanmax(w):.2f}; {np.isnan(w).sum()} of {len(w)} "
              f"positions without a direct sink); the paper's implied: "
              + ", ".join(f"{v:.2f}" for v in implied[name])
              + f" deg (median {np.median(implied[name]):.2f}, "
              f"{np.median(implied[name]) / np.nanmedian(w):.2f} of ours)", flush=True)
        gains = ds.kappa[0] * np.array([0.85, 0.92, 1.0, 1.1, 1.2, 1.35])
        for k, w in zip(gains, widths_at_gains(teacher, ds, gains)):
            print(f"  at kappa {k:.2f} ({k / ds.kappa[0]:.2f} x the teacher's): intervals "
                  f"{np.median(w):.2f} deg wide at the median of 10 situations "
                  f"({np.sum(w == 0)} without a sink)", flush=True)
        for fac in args.factors:
            results[(name, fac)] = run(name, ds, sink, holes, lower, upper, fac,
                                       args.repetitions)
        means, _ = run_table1({name: (f, ds)}, args.repetitions, 0, sinking={name: sink})
        simulated[name] = {(r.training, r.model): r.success_rate for r in means}
    print(f"\nsuccess over {args.repetitions} repetitions; intervals narrowed by f "
          f"(f = 1, 'ball': the protocol played on the ball model)")
    head = " ".join(f"{'f=' + format(v, 'g'):>7}" for v in args.factors)
    print(f"{'field':<12} {'training':<18} {'model':<6} {'ball':>6} {head} {'paper':>6}")
    within = {fac: 0 for fac in args.factors}
    within_ball = 0
    for name in fields:
        for label, _, _ in PAPER_TRAINING_SETS[1]:
            for model in ("gpr", "gmr"):
                paper = PAPER_TABLE1[(name, label, model)][2]
                vals = [results[(name, fac)][(label, model)] for fac in args.factors]
                ball = simulated[name][(label, model)]
                within_ball += abs(ball - paper) <= 0.1 + 1e-9
                for fac, v in zip(args.factors, vals):
                    within[fac] += abs(v - paper) <= 0.1 + 1e-9
                print(f"{name:<12} {label:<18} {model:<6} {ball:>6.2f} "
                      + " ".join(f"{v:>7.2f}" for v in vals) + f" {paper:>6.2f}")
    print(f"{f'within 0.1 (of {6 * len(fields)})':<38} {within_ball:>6d} "
          + " ".join(f"{within[fac]:>7d}" for fac in args.factors))
    for fac in args.factors:
        ok = all(results[(n, fac)][(t, "gmr")] >= results[(n, fac)][(t, "gpr")]
                 for n in fields for t in ("5 random", "10 random"))
        sp = all(results[(n, fac)][("10 equally spaced", "gpr")]
                 >= results[(n, fac)][("10 equally spaced", "gmr")] for n in fields)
        print(f"f = {fac:g}: random GMR >= GPR {'holds' if ok else 'no'}; spaced GPR >= GMR "
              f"{'holds' if sp else 'no'}")
    print(f"{time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
