"""Minigolf: fields (shipped and the user's own JSON files), the ball model (rolling, skidding,
walls, hole capture; numpy reference and compiled engines), the teacher that finds good shots,
the hitting-parameter learners (GPR, GMR) and the protocol of the paper's Table 1. It imports
:mod:`seds_casadi.motion`, :mod:`seds_casadi.core` and :mod:`seds_casadi.codegen`.
"""

from .ball import ShotResult, impact, simulate_shots
from .fields import Field, field_names, load_field
from .parameters import GMRModel, GPRModel, make_model
from .table1 import run_table1
from .teacher import HittingDataset, Stroke, Teacher, collect_dataset, success_map

__all__ = ["Field", "load_field", "field_names", "simulate_shots", "impact", "ShotResult",
           "Stroke", "Teacher", "HittingDataset", "collect_dataset", "success_map",
           "GPRModel", "GMRModel", "make_model", "run_table1"]
