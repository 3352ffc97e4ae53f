"""Self-correction (issue 32): test success before and after ``--adapt N`` shots on worlds
whose green differs from the field the robot was taught on, GPR and GMR.

    python benchmarks/eval_self_correction.py [--adapt 30] [--shots 20] [--out DIR]

Runs ``seds-casadi play --field F --world W --adapt N --validate 0`` (the API, the same code)
for the shipped worlds (``fields/worlds``), ``--world exudyn``, the nominal field itself (no
regression), taller hills on double hill (outside the green's five parameters; the passage
residual was developed on it), two worlds written after the method was settled, not tuned for
(a taller arctan step, outside the five parameters too, and a rough flat green at stimp 12),
a world beyond the arm (rough flat at stimp 8: its far holes
need a faster launch than the WAM's swing gives) and, from nothing, arctan played by a robot
taught on a flat guess of its course; prints the success after 0, 1, 2, 5, 10, 20 and N
shots and a table. Takes about 3 minutes per world on 2 cores.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time

from seds_casadi.app.play import play
from seds_casadi.minigolf.fields import FIELDS_FOLDER


def _world(src: str, name: str, folder: str, **change) -> str:
    with open(os.path.join(FIELDS_FOLDER, src + ".json")) as fh:
        d = json.load(fh)
    d["name"] = name
    for k, v in change.items():
        d[k] = v
    path = os.path.join(folder, name + ".json")
    with open(path, "w") as fh:
        json.dump(d, fh)
    return path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--adapt", type=int, default=30)
    ap.add_argument("--shots", type=int, default=20)
    ap.add_argument("--out", default=os.path.join(tempfile.gettempdir(), "self_correction"))
    ap.add_argument("--only", nargs="*", default=None, help="run only these world labels")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(FIELDS_FOLDER, "double_hill.json")) as fh:
        hills = json.load(fh)["surface"]
    for h in hills["hills"]:
        h["height"] = round(h["height"] * 1.3, 4)
    with open(os.path.join(FIELDS_FOLDER, "arctan.json")) as fh:
        step = json.load(fh)["surface"]
    step["height"] = round(step["height"] * 1.3, 4)
    cases = [
        ("arctan", "arctan_stimp8", "slower green (stimp 8 for 10)"),
        ("flat", "flat_tilted", "tilted 1 % sideways"),
        ("double_hill", "double_hill_stimp12", "faster green (stimp 12 for 10)"),
        ("arctan", "exudyn", "exudyn's multibody model"),
        ("arctan", None, "the field itself (no regression)"),
        ("double_hill", _world("double_hill", "double_hill_tall", a.out, surface=hills),
         "outside the model: hills 30 % taller"),
        ("rough_flat", _world("rough_flat", "rough_flat_stimp12", a.out, stimp=12),
         "untuned: rough flat at stimp 12"),
        ("arctan", _world("arctan", "arctan_taller", a.out, surface=step),
         "untuned: arctan's step 30 % taller"),
        ("rough_flat", _world("rough_flat", "rough_flat_stimp8", a.out, stimp=8),
         "beyond the WAM: rough flat at stimp 8"),
        (_world("arctan", "arctan_flat_guess", a.out,
                surface={"shape": "plane", "slope_x": 0.0, "slope_y": 0.0}),
         os.path.join(FIELDS_FOLDER, "arctan.json"), "from nothing: taught on a flat guess"),
    ]
    rows = []
    for field, world, what in cases:
        label = os.path.basename(str(world)).removesuffix(".json")
        if a.only and label not in a.only:
            continue
        t = time.perf_counter()
        res = play(field=field, world=world, adapt=a.adapt, shots=a.shots, validate_shots=0,
                   out=os.path.join(a.out, f"{field}_{label}"), progress=False)
        tests = [r for r in res["all_rows"] if r["phase"] == "test"]
        curve = {m: {k: sum(r["sunk"] for r in tests
                            if r["method"] == m and r["adapt_shots"] == k) / a.shots
                     for k in sorted({r["adapt_shots"] for r in tests})} for m in ("gpr", "gmr")}
        before = {m: curve[m][0] for m in curve}
        field = os.path.basename(field).removesuffix(".json")
        rows.append((field, label, what, before, res["success"], time.perf_counter() - t))
        print(f"{field:12s} {label:22s} {what:36s} before gpr {before['gpr']:.2f} gmr "
              f"{before['gmr']:.2f} | after {a.adapt}: gpr {res['success']['gpr']:.2f} gmr "
              f"{res['success']['gmr']:.2f} ({rows[-1][-1]:.0f} s)", flush=True)
        for m in curve:
            print(f"    {m} sunk after k adaptation shots: "
                  + ", ".join(f"{k}: {v:.2f}" for k, v in curve[m].items()), flush=True)
    print(f"\n| field | world | before GPR | before GMR | after {a.adapt} GPR | after GMR |")
    print("|---|---|---|---|---|---|")
    for field, label, what, b, f, _ in rows:
        print(f"| {field} | {label} ({what}) | {b['gpr']:.2f} | {b['gmr']:.2f} | "
              f"{f['gpr']:.2f} | {f['gmr']:.2f} |")


if __name__ == "__main__":
    main()
