"""Benchmark: the main job's stages (``seds-casadi play --no-cache`` on its defaults: the WAM on
arctan, 20 situations, GPR and GMR, 2 shots checked in exudyn), median over repeats.

Each run is a fresh interpreter (``python -m seds_casadi play --no-cache``, the
compiled C kernels taken from their cache as on a user's second run) whose ``summary.txt``
gives the seconds of each stage; the wall time of the whole command is measured here. With
``--baseline DIR`` the same command runs, alternating with this checkout's, on the code in DIR
(a checkout of an earlier commit, e.g. ``git worktree add /tmp/before e360d10``), so both are
measured side by side on the same machine state; the folders ``fields`` and ``robots`` are
linked into DIR's package as an installed package has them.

Usage: python benchmarks/bench_play_stages.py [--repeats 3] [--baseline DIR] [-- PLAY OPTIONS]
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parents[1]


def _link_data(src: Path) -> None:
    """An uninstalled checkout: make its package find the field and robot files."""
    for pkg, folder in (("_fields", "fields"), ("_robots", "robots")):
        link = src / "seds_casadi" / pkg
        if not link.exists():
            link.symlink_to(Path("..") / folder)


def run_once(src: Path, extra: list[str]) -> dict[str, float]:
    """One ``play --no-cache`` with the package of ``src``; stage -> seconds, plus the wall
    time (``wall``)."""
    with tempfile.TemporaryDirectory() as out:
        env = dict(os.environ, PYTHONPATH=str(src), MPLBACKEND="Agg")
        t0 = time.perf_counter()
        r = subprocess.run([sys.executable, "-m", "seds_casadi", "play", "--no-cache",
                            "--out", out, *extra], env=env, cwd=out,
                           capture_output=True, text=True, timeout=1800)
        wall = time.perf_counter() - t0
        if r.returncode != 0:
            raise SystemExit(f"play failed with {src}:\n{r.stderr[-3000:]}")
        text = Path(out, "summary.txt").read_text()
    stages = {m.group(1): float(m.group(2))
              for m in re.finditer(r"^  (.+?): ([0-9.]+) s$", text, re.M)}
    stages["wall (the command)"] = wall
    sunk = re.findall(r"^  (\w+): (\d+)% sunk$", text, re.M)
    stages.update({f"{m} sunk [%]": float(v) for m, v in sunk})
    return stages


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--baseline", help="a checkout of an earlier commit to time side by side")
    ap.add_argument("play_options", nargs="*", help="more options of play (after --)")
    a = ap.parse_args()
    if a.repeats < 1:
        ap.error("--repeats must be at least 1")
    sources = {"this checkout": HERE}
    if a.baseline:
        base = Path(a.baseline).resolve()
        if not (base / "seds_casadi" / "__init__.py").exists():
            ap.error(f"--baseline {base}: no seds_casadi package there")
        _link_data(base)
        sources = {"baseline": base, **sources}
    runs: dict[str, list[dict]] = {k: [] for k in sources}
    for i in range(a.repeats):
        for name, src in sources.items():
            runs[name].append(run_once(src, a.play_options))
            print(f"run {i + 1}/{a.repeats} {name}: "
                  f"{runs[name][-1]['wall (the command)']:.1f} s", flush=True)
    stages: list[str] = []
    for rs in runs.values():
        for r in rs:
            stages += [s for s in r if s not in stages]
    print(f"\nmedian of {a.repeats} (seconds; success in %)")
    print(f"{'stage':<42}" + "".join(f"{n:>16}" for n in runs))
    for s in stages:
        cells = []
        for rs in runs.values():
            v = [r[s] for r in rs if s in r]
            cells.append(f"{np.median(v):16.1f}" if v else f"{'-':>16}")
        print(f"{s:<42}" + "".join(cells))


if __name__ == "__main__":
    main()
