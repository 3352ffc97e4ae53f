"""Benchmark (issue 14): SEDS with P = I, with a learned P, and the constrained form, same run.

The ds-opt LASA protocol (:func:`seds_casadi.app.lasa.evaluate_shape_dsopt`: demos 1-4 train,
5-7 test, every 2nd sample, ds-opt's RMSE, e_dot and DTWD) for each variant of the learner on
the same shapes and K, beside the published SEDS and LPV-DS means; the per-shape test figures
of the shapes where SEDS is furthest behind; the constrained form against the by-construction
form (objective reached, iterations, time, IPOPT failures, certified). With ``--figures``:
streamlines and level sets of V(x) = (x - x*)^T P (x - x*) for P = I and the learned P.

Usage::

    python benchmarks/bench_lyapunov.py                          # 26 shapes, plain and learned
    python benchmarks/bench_lyapunov.py --variants plain learned constrained constrained-learned \\
        --shapes Leaf_1 JShape BendedLine WShape
    python benchmarks/bench_lyapunov.py --figures --shapes Leaf_1 JShape --out docs
    python benchmarks/bench_lyapunov.py --variants plain learned-g10 --repeats 10   # seed means
"""

from __future__ import annotations

import argparse
import os
import time
import warnings

import numpy as np

VARIANTS = {
    "plain": {},
    "learned": {"lyapunov": "learned"},
    "plain-g10": {"gain_limit": 10.0},
    "learned-g10": {"lyapunov": "learned", "gain_limit": 10.0},
    "constrained": {"formulation": "constrained"},
    "constrained-learned": {"formulation": "constrained", "lyapunov": "learned"},
    "constrained-g10": {"formulation": "constrained", "gain_limit": 10.0},
    "plain-lpv": {"init": "lpv"},
    "learned-lpv": {"lyapunov": "learned", "init": "lpv"},
    "learned-g10-lpv": {"lyapunov": "learned", "gain_limit": 10.0, "init": "lpv"},
    # IPOPT's adaptive barrier update (SEDS(solver_options=...))
    "plain-adaptive": {"solver_options": {"mu_strategy": "adaptive"}},
    "learned-g10-adaptive": {"lyapunov": "learned", "gain_limit": 10.0,
                             "solver_options": {"mu_strategy": "adaptive"}},
    # the direction objective (Eq. 9) with its strength factor (Eq. 12) for the speeds
    "direction": {"objective": "direction"},
    "direction-g10": {"objective": "direction", "gain_limit": 10.0},
    "learned-direction": {"objective": "direction", "lyapunov": "learned"},
    "learned-g10-direction": {"objective": "direction", "lyapunov": "learned",
                              "gain_limit": 10.0},
    # PC-GMM's physically-consistent clustering, the GMM then fixed (LPV-DS's split) or free
    "pc-fixed": {"init": "pc", "gmm": "fixed"},
    "learned-g10-pc-fixed": {"lyapunov": "learned", "gain_limit": 10.0, "init": "pc",
                             "gmm": "fixed"},
    "learned-g10-pc-joint": {"lyapunov": "learned", "gain_limit": 10.0, "init": "pc"},
    # ... with K chosen on the training demos (leave one demonstration out)
    "cv-k-learned-g10-pc-fixed": {"lyapunov": "learned", "gain_limit": 10.0, "init": "pc",
                                  "gmm": "fixed", "param_grid": {"n_components": [4, 5, 6, 7, 8]}},
    # DemoSearchCV on the training demos (leave one out) chooses the objective, then refits
    "cv-learned-g10": {"lyapunov": "learned", "gain_limit": 10.0,
                       "param_grid": {"objective": ["mse", "direction"]}},
    "cv-g10": {"gain_limit": 10.0, "param_grid": {"objective": ["mse", "direction"],
                                                  "lyapunov": ["identity", "learned"]}},
}
NAMED = ("BendedLine", "Leaf_1", "JShape", "WShape")


def _one(args):
    shape, variant, K, seed, max_iter = args
    from seds_casadi.app.lasa import evaluate_shape_dsopt

    warnings.simplefilter("ignore")
    t0 = time.perf_counter()
    try:
        opts = dict(VARIANTS[variant])
        objective = opts.pop("objective", "mse")
        grid = opts.pop("param_grid", None)
        train, test = evaluate_shape_dsopt(shape, objective=objective, n_components=K,
                                           random_state=seed, max_iter=max_iter,
                                           seds_options=opts, param_grid=grid)
    except Exception as exc:  # noqa: BLE001 - a failed fit is a result of the benchmark
        return {"shape": shape, "variant": variant, "error": f"{type(exc).__name__}: {exc}",
                "seconds": time.perf_counter() - t0}
    return {"shape": shape, "variant": variant, "train_rmse": train.rmse_mmps,
            "rmse": test.rmse_mmps, "e_dot": test.e_dot, "dtwd": test.dtwd_mm,
            "seconds": test.seconds, "iterations": test.iterations, "status": test.status,
            "objective": test.objective_value, "chosen": test.chosen,
            "certified": test.certified, "pub": (test.published_rmse_mmps, test.published_e_dot,
                                                 test.published_dtwd_mm)}


def _mean_over_seeds(rows: list[dict]) -> list[dict]:
    """One row per (shape, variant): metrics and objective averaged over the seeds that ran,
    time and iterations their medians; a seed that failed makes the row an error."""
    out = []
    keys = list(dict.fromkeys((r["shape"], r["variant"]) for r in rows))
    for shape, variant in keys:
        rs = [r for r in rows if r["shape"] == shape and r["variant"] == variant]
        errs = [r for r in rs if "error" in r]
        if errs:
            out.append(dict(errs[0], error=f"{len(errs)}/{len(rs)} seeds failed: "
                                             f"{errs[0]['error']}"))
            continue
        m = dict(rs[0])
        for k in ("rmse", "e_dot", "dtwd", "train_rmse", "objective"):
            m[k] = float(np.mean([r[k] for r in rs]))
        for k in ("seconds", "iterations"):
            m[k] = float(np.median([r[k] for r in rs]))
        m["iterations"] = int(m["iterations"])
        m["certified"] = all(r["certified"] for r in rs)
        bad = [r["status"] for r in rs
               if r["status"] not in ("Solve_Succeeded", "Solved_To_Acceptable_Level")]
        m["status"] = bad[0] if bad else rs[0]["status"]
        if rs[0].get("chosen"):
            picks = [r["chosen"] for r in rs]
            m["chosen"] = "; ".join(f"{c} x{picks.count(c)}" for c in dict.fromkeys(picks))
        out.append(m)
    return out


def _figures(shapes, K, seed, out):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from seds_casadi import SEDS
    from seds_casadi.app.lasa import dsopt_sets

    for shape in shapes:
        sets = dsopt_sets(shape)
        demos = sets["train"].demonstrations()
        fig, axes = plt.subplots(1, 2, figsize=(11, 4.8), constrained_layout=True)
        for ax, (name, opts) in zip(axes, (("P = I (SEDS)", {}),
                                           ("learned P", {"lyapunov": "learned"}))):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                m = SEDS(K, objective="mse", random_state=seed, **opts).fit(demos).model_
            allx = np.concatenate(sets["train"].positions + sets["test"].positions)
            lo, hi = allx.min(0), allx.max(0)
            pad = 0.15 * (hi - lo)
            gx = np.linspace(lo[0] - pad[0], hi[0] + pad[0], 60)
            gy = np.linspace(lo[1] - pad[1], hi[1] + pad[1], 60)
            GX, GY = np.meshgrid(gx, gy)
            pts = np.c_[GX.ravel(), GY.ravel()]
            F = m.predict(pts)
            ax.streamplot(GX, GY, F[:, 0].reshape(GX.shape), F[:, 1].reshape(GX.shape),
                          color="0.6", density=1.2, linewidth=0.7, arrowsize=0.8)
            P = m.lyapunov_matrix
            E = pts - m.target
            V = np.einsum("ni,ij,nj->n", E, P, E).reshape(GX.shape)
            cs = ax.contour(GX, GY, V, levels=8, colors="tab:purple", linewidths=0.9)
            ax.clabel(cs, fontsize=6, fmt="%.0f")
            for p in sets["train"].positions:
                ax.plot(p[:, 0], p[:, 1], color="tab:red", lw=1.6)
            for p in sets["test"].positions:
                ax.plot(p[:, 0], p[:, 1], color="tab:orange", lw=1.2, ls="--")
            for n, p in enumerate(sets["test"].positions):
                path = m.rollout(p[19], dt=0.01, max_steps=3000, warn=False)
                ax.plot(path[:, 0], path[:, 1], color="tab:blue", lw=1.4,
                        label="reproduction (test starts)" if n == 0 else None)
            ax.plot(*m.target, "k*", ms=10)
            ax.set_title(f"{shape}, K={K}, {name}; cond(P) = {np.linalg.cond(P):.1f}")
            ax.set_xlabel("x [mm]")
            ax.set_ylabel("y [mm]")
            ax.set_aspect("equal", adjustable="box")
            ax.plot([], [], color="tab:red", label="training demos")
            ax.plot([], [], color="tab:orange", ls="--", label="test demos")
            ax.plot([], [], color="tab:purple", label="level sets of V = e^T P e")
            ax.legend(fontsize=7, loc="best")
        path = os.path.join(out, f"lyapunov_{shape}.png")
        fig.savefig(path, dpi=110)
        plt.close(fig)
        print("wrote", path)


def main(argv: list[str] | None = None) -> int:
    from seds_casadi.app.lasa import PUBLISHED_MEANS
    from seds_casadi.core.datasets import LASA_SINGLE_SHAPES

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shapes", nargs="+", default=list(LASA_SINGLE_SHAPES))
    ap.add_argument("--variants", nargs="+", choices=list(VARIANTS),
                    default=["plain", "learned"])
    ap.add_argument("-K", type=lambda t: t if t == "published" else int(t), default=4,
                    help="components, or 'published' (the published runs' K per shape) [4]")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--repeats", type=int, default=1,
                    help="seeds per shape (seed, seed + 1, ...); the figures are then means "
                         "over them, as the published runs' (10 repetitions) [1]")
    ap.add_argument("--max-iter", type=int, default=1000)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--figures", action="store_true")
    ap.add_argument("--out", default="bench_lyapunov_out")
    a = ap.parse_args(argv)
    os.makedirs(a.out, exist_ok=True)
    if a.figures:
        _figures(a.shapes, a.K, a.seed, a.out)
        return 0
    seeds = range(a.seed, a.seed + a.repeats)
    tasks = [(s, v, a.K, seed, a.max_iter) for v in a.variants for s in a.shapes
             for seed in seeds]
    t0 = time.perf_counter()
    if a.workers > 1:
        # the project's executor: its workers sum on one thread each (SEDS_CASADI_THREADS=1),
        # as `seds-casadi lasa` does; a bare process pool gave each worker two threads on two
        # cores (oversubscribed, and a different summation order, so slightly other optima)
        from seds_casadi.app.executors import open_executor

        with open_executor(a.workers) as ex:
            rows = list(ex.map(_one, tasks))
    else:
        rows = [_one(t) for t in tasks]
    wall = time.perf_counter() - t0
    n_fits = len(rows)
    if a.repeats > 1:
        rows = _mean_over_seeds(rows)
    print(f"ds-opt protocol, test demos, K = {a.K}, {len(a.shapes)} shapes, wall {wall:.0f} s"
          + (f", {a.repeats} seeds per shape ({n_fits} runs; figures are means over seeds, "
             "as the published SEDS runs' 10 repetitions)" if a.repeats > 1 else ""))
    print(f"{'variant':<22} {'ok':>5} {'RMSE':>7} {'e_dot':>7} {'DTWD':>8} {'median s':>9} "
          f"{'iter':>6} {'unconv':>6} {'cert':>5}")
    for v in a.variants:
        rs = [r for r in rows if r["variant"] == v and "error" not in r]
        n_err = sum(1 for r in rows if r["variant"] == v and "error" in r)
        if rs:
            m = np.mean([[r["rmse"], r["e_dot"], r["dtwd"]] for r in rs], axis=0)
            unconv = sum(r["status"] not in ("Solve_Succeeded", "Solved_To_Acceptable_Level")
                         for r in rs)
            print(f"{v:<22} {len(rs):>2}/{len(rs) + n_err:<2} {m[0]:>7.2f} {m[1]:>7.3f} "
                  f"{m[2]:>8.0f} {np.median([r['seconds'] for r in rs]):>9.1f} "
                  f"{np.median([r['iterations'] for r in rs]):>6.0f} {unconv:>6} "
                  f"{sum(r['certified'] for r in rs):>5}")
        for r in rows:
            if r["variant"] == v and "error" in r:
                print(f"    {r['shape']}: {r['error'][:150]}")
    shapes_ok = [s for s in a.shapes if all(
        any(r["shape"] == s and r["variant"] == v and "error" not in r for r in rows)
        for v in a.variants)]
    pub = np.mean([next(r["pub"] for r in rows if r["shape"] == s and "pub" in r)
                   for s in shapes_ok], axis=0) if shapes_ok else [np.nan] * 3
    print(f"{'published SEDS, same':<22} {len(shapes_ok):>5} {pub[0]:>7.2f} {pub[1]:>7.3f} "
          f"{pub[2]:>8.0f}")
    for (method, st), vals in PUBLISHED_MEANS.items():
        if st == "test":
            print(f"  published {method} (26 shapes): RMSE {vals[0]:.2f}, e_dot {vals[1]:.3f}, "
                  f"DTWD {vals[2]:.0f}")
    print("\nshapes above 1.5x the published SEDS figure on some metric (RMSE, e_dot, DTWD):")
    for v in a.variants:
        over = []
        for r in rows:
            if r["variant"] == v and "error" not in r:
                bad = [n for n, x, p in zip(("RMSE", "e_dot", "DTWD"),
                                            (r["rmse"], r["e_dot"], r["dtwd"]), r["pub"])
                       if x > 1.5 * p]
                if bad:
                    over.append(f"{r['shape']} ({', '.join(bad)})")
        print(f"  {v}: {len(over)}" + (f": {'; '.join(over)}" if over else ""))
    print("\nper shape (test): RMSE / e_dot / DTWD, J = the training objective reached (scaled "
          "units); published SEDS last")
    for s in a.shapes:
        cells = []
        for v in a.variants:
            r = next(r for r in rows if r["shape"] == s and r["variant"] == v)
            cells.append("failed" if "error" in r else
                         f"{r['rmse']:6.2f} {r['e_dot']:.3f} {r['dtwd']:7.0f} J {r['objective']:.4f}"
                         f" ({r['seconds']:.0f} s, {r['iterations']} it)"
                         + (f" [{r['chosen']}]" if r.get("chosen") else ""))
        p = next((r["pub"] for r in rows if r["shape"] == s and "pub" in r), (np.nan,) * 3)
        mark = "*" if s in NAMED else " "
        print(f"{mark}{s:<17} " + " | ".join(cells) + f" | {p[0]:.2f} {p[1]:.3f} {p[2]:.0f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
