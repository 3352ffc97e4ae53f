"""Paper Table 1 with Fig. 10 and 11: GPR against GMR for the hitting parameters.

The same as ``seds-casadi table1`` (see its --help), from the API: learn the hitting motion,
let the teacher collect good shots on each field (as the paper's simulator modelled it: the
rough flat field without its grass structure, Section 7.2.2), measure the sinking set around
them, run the paper's protocol (noisy examples drawn from the sinking set, Eq. 15; random
training points from the centred range, Fig. 10; GPR with Eq. 17a's zero mean), print the
table beside the paper's numbers with the paper's conclusions checked, and draw Fig. 10 (GPR
and GMR with 2-sigma bands on the double hill data) and Fig. 11 (the joint GMM on the arctan
data).

python examples/table1_gpr_vs_gmr.py [--out examples_out/table1.png] [--repetitions 100] [--workers 2]
                                     [--protocol paper|grid] [--quick]
"""

import argparse
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from seds_casadi.app.executors import open_executor
from seds_casadi.app.table1 import fig10, fig11
from seds_casadi.minigolf import Stroke, collect_dataset
from seds_casadi.minigolf.fields import load_field
from seds_casadi.minigolf.sinking import sinking_set
from seds_casadi.minigolf.table1 import PROTOCOLS, format_table1, run_table1, simulated_field
from seds_casadi.minigolf.teacher import Teacher
from seds_casadi.motion.hitting import HittingMotionLearner
from seds_casadi.motion.putting_demos import load_hitting_demos

ap = argparse.ArgumentParser()
ap.add_argument("--out", default="examples_out/table1.png",
                help="the figure's file; its folder is made [examples_out/table1.png]")
ap.add_argument("--repetitions", type=int, default=100)
ap.add_argument("--workers", type=int, default=1)
ap.add_argument("--protocol", choices=PROTOCOLS, default="paper")
ap.add_argument("--quick", action="store_true", help="2 repetitions, coarse teacher (CI)")
args = ap.parse_args()
os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)

stroke = Stroke.from_motion(HittingMotionLearner().fit(load_hitting_demos()).motion_)
teacher = {"resolution": (81, 26)} if args.quick else {}
fields = ["double_hill", "arctan"] if args.quick else ["rough_flat", "double_hill", "arctan"]
datasets, sinking = {}, {}
for name in fields:
    f = load_field(name)
    if args.protocol == "paper":
        f = simulated_field(f)  # as the paper's simulator modelled it (no grass structure)
    datasets[name] = (f, collect_dataset(f, stroke, progress=True, **teacher))
    # the parameters around each good shot that sink the ball too (Eq. 15's noise)
    scan = {"n_gains": 3, "step_deg": 0.05} if args.quick else {}
    sinking[name] = sinking_set(Teacher(f, stroke, **teacher), datasets[name][1], **scan)
with open_executor(args.workers) as ex:
    means, _ = run_table1(datasets, 2 if args.quick else args.repetitions, executor=ex,
                          progress=True, protocol=args.protocol, sinking=sinking)
table = format_table1(means)
print(table)
with open(os.path.splitext(args.out)[0] + ".txt", "w", encoding="utf-8") as fh:
    fh.write(table)

fig = plt.figure(figsize=(11, 7.6))
noisy = args.protocol == "paper"
fig10("double_hill", datasets["double_hill"][1],
      ax_row=[fig.add_subplot(2, 2, 1), fig.add_subplot(2, 2, 2)],
      sinking=sinking["double_hill"] if noisy else None)
fig11(datasets["arctan"][1], ax_row=[fig.add_subplot(2, 4, 5 + i) for i in range(4)],
      sinking=sinking["arctan"] if noisy else None)
fig.suptitle("Fig. 10 (top): GPR and GMR on the double hill, 10 random points of the centred "
             "range; Fig. 11 (bottom): joint GMM, arctan")
fig.subplots_adjust(hspace=0.45)
fig.savefig(args.out, dpi=110, bbox_inches="tight")
print(f"wrote {args.out}")
