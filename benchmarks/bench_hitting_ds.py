"""Benchmark: one evaluation of the steered hitting DS (Eq. 14) from Python.

Eq. 14 is defined once, as the CasADi Function of ``HittingMotion.to_casadi()``; this times, side
by side in one run, the ways it is evaluated: ``HittingMotion.velocity`` at one point (input
checks and CasADi's map over columns, the path for many points), the Function called directly
in CasADi's virtual machine and through fixed buffers (``FastEvaluator``, the rollouts' path),
and the same Function compiled to C (code generation + the system compiler) and loaded with
``casadi.external`` (``HittingMotion.compiled()``: the controller's path).

Usage: python benchmarks/bench_hitting_ds.py [--repeat 20000]
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import tempfile
import time

import casadi as ca
import numpy as np

from seds_casadi.codegen import FastEvaluator
from seds_casadi.motion import HittingMotionLearner, load_hitting_demos


def median_us(fn, repeat: int) -> float:
    times = np.empty(repeat)
    for i in range(repeat):
        t0 = time.perf_counter()
        fn()
        times[i] = time.perf_counter() - t0
    return float(np.median(times) * 1e6)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=20000)
    args = ap.parse_args()
    motion = HittingMotionLearner().fit(load_hitting_demos()).motion_
    x = np.array([-0.3, 0.05, 0.1])
    alpha, kappa = 0.2, 1.1
    f = motion.to_casadi()
    out = {}
    out["HittingMotion.velocity"] = median_us(lambda: motion.velocity(x, alpha, kappa),
                                              args.repeat)
    out["CasADi virtual machine"] = median_us(lambda: f(x, alpha, kappa), args.repeat)
    vm = FastEvaluator(f)
    out["virtual machine, buffers (rollouts)"] = median_us(lambda: vm(x, alpha, kappa),
                                                           args.repeat)
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc:
        tmp = tempfile.mkdtemp()
        try:
            gen = ca.CodeGenerator("hitting_ds.c", {"with_header": False})
            gen.add(f)
            gen.generate(tmp + os.sep)
            lib = os.path.join(tmp, "hitting_ds.so")
            subprocess.run([cc, "-shared", "-fPIC", "-O2", os.path.join(tmp, "hitting_ds.c"),
                            "-o", lib], check=True)
            fc = ca.external(f.name(), lib)
            np.testing.assert_allclose(np.asarray(fc(x, alpha, kappa)).ravel(),
                                       motion.velocity(x, alpha, kappa), rtol=1e-10)
            out["compiled C (casadi.external)"] = median_us(lambda: fc(x, alpha, kappa),
                                                            args.repeat)
            # the same compiled function called without Python's argument conversion overhead
            buf_in = [ca.DM(x), ca.DM(alpha), ca.DM(kappa)]
            out["compiled C, DM arguments"] = median_us(lambda: fc.call(buf_in), args.repeat)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
    fast = motion.compiled()
    np.testing.assert_allclose(fast(x, alpha, kappa), motion.velocity(x, alpha, kappa),
                               rtol=1e-10)
    out["HittingMotion.compiled() (buffers)"] = median_us(lambda: fast(x, alpha, kappa),
                                                          args.repeat)
    base = out["HittingMotion.velocity"]
    print(f"one evaluation of Eq. 14, median over {args.repeat} calls:")
    for name, us in out.items():
        print(f"  {name:<36} {us:8.2f} us   ({base / us:6.1f}x velocity)")


if __name__ == "__main__":
    main()
