"""Minigolf: fields (``fields``, shipped and the user's own JSON files; their ``surface`` and
the ``situations`` they declare), the ball model (``ball``: rolling, skidding, walls, hole
capture and the numpy reference; ``ball_kernel``: the compiled engine), the hit (``stroke``),
the teacher that finds good shots (``teacher``), its data sets (``hitting_data``) and the
sinking set around its shots that noisy examples are drawn from (``sinking``, Eq. 15), the
hitting-parameter learners (``parameters``: GPR, GMR), the protocol of the paper's Table 1
(``table1``) and several strategies (``strategies``: explored and clustered;
``strategy_choice``: the one most likely to succeed). It imports :mod:`seds_casadi.motion`,
:mod:`seds_casadi.core` and :mod:`seds_casadi.codegen`.
"""

from .ball import impact, simulate_shots
from .ball_physics import ShotResult
from .fields import Field, field_names, load_field
from .hitting_data import HittingDataset
from .parameters import GMRModel, GPRModel, make_model
from .stroke import Stroke
from .table1 import run_table1
from .teacher import Teacher, collect_dataset, success_map

__all__ = ["Field", "load_field", "field_names", "simulate_shots", "impact", "ShotResult",
           "Stroke", "Teacher", "HittingDataset", "collect_dataset", "success_map",
           "GPRModel", "GMRModel", "make_model", "run_table1"]
