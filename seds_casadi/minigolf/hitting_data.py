"""Good shots for a field: the teacher's situations (:func:`paper_situations`, drawn from the
field's declared situations) and the data set of the teacher's hitting parameters
(:class:`HittingDataset`, saved as ``.npz`` without pickle, the angle in degrees).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from ..core.errors import ModelFileError
from ..core.model_files import read_guarded, write_guarded
from .fields import TEACHER_STRATEGIES, Field
from .stroke import Stroke

__all__ = ["HittingDataset", "paper_situations", "region_centre", "DATASET_VERSION",
           "DATASET_FORMAT"]

#: version of the guarded ``.npz`` format written by :meth:`HittingDataset.save` (1 and 2, of
#: earlier releases, had no checksum and are refused: regenerate them)
DATASET_VERSION = 3
#: the ``format`` entry of a data set file
DATASET_FORMAT = "seds_casadi.HittingDataset"
_SCHEMA = {"ball": 2, "hole": 2, "alpha_deg": 1, "kappa": 1, "labels": (1, "i")}


def region_centre(region) -> np.ndarray:
    """The centre (x, y) of a box [xmin, xmax, ymin, ymax]."""
    return np.array([(region[0] + region[1]) / 2, (region[2] + region[3]) / 2])


def paper_situations(field: Field, n: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The teacher's situations for a field: balls and holes, each shape (m, 2).

    They are spread over the situations the field declares
    (:meth:`~seds_casadi.minigolf.situations.Situations.design`): by default the paper's
    sizes, 20 equally spaced along a one-dimensional situation space (the hole moved along a
    slider, Fig. 9) and a grid of 56 over a two-dimensional one (the ball over its region on
    arctan, 7 x 8).
    """
    return field.situations.design(n)


@dataclass
class HittingDataset:
    """Good shots for a field: situations and the teacher's (alpha, kappa).

    Attributes
    ----------
    field : str
    strategy : str
        The teacher's rule (``"fixed_speed"``, ``"minimal_speed"``, ``"centre"``).
    ball, hole : array, shape (n, 2)
    alpha : array, shape (n,)
        Hitting angles [rad] (:attr:`alpha_deg` in degrees, as saved and as the learners see
        them).
    kappa : array, shape (n,)
    stroke : Stroke
    dropped : int
        Situations where the teacher found no successful hit (left out).
    labels : array of int, shape (n,)
        The strategy each shot belongs to (0 for a data set of one strategy; see
        :mod:`seds_casadi.minigolf.strategies`).
    declared : dict
        The field's ``"situations"`` declaration the data set was drawn from.
    """

    field: str
    strategy: str
    ball: np.ndarray
    hole: np.ndarray
    alpha: np.ndarray
    kappa: np.ndarray
    stroke: Stroke
    dropped: int = 0
    labels: np.ndarray | None = None
    declared: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.labels = (np.zeros(len(self.alpha), int) if self.labels is None
                       else np.asarray(self.labels, int))

    def __len__(self) -> int:
        return len(self.alpha)

    @property
    def alpha_deg(self) -> np.ndarray:
        """Hitting angles [deg]."""
        return np.rad2deg(self.alpha)

    @property
    def situations(self) -> np.ndarray:
        """s = hole - ball, shape (n, 2): the learners' input."""
        return self.hole - self.ball

    @property
    def outputs(self) -> np.ndarray:
        """What the learners predict: alpha [deg] for fixed speed, (alpha [deg], kappa) else."""
        a = self.alpha_deg
        return a[:, None] if self.strategy == "fixed_speed" else np.column_stack([a, self.kappa])

    def subset(self, keep) -> HittingDataset:
        """The data set restricted to the rows ``keep`` (indices or a boolean mask)."""
        k = np.asarray(keep)
        return HittingDataset(self.field, self.strategy, self.ball[k], self.hole[k],
                              self.alpha[k], self.kappa[k], self.stroke, self.dropped,
                              self.labels[k], dict(self.declared))

    def save(self, path: str | os.PathLike) -> None:
        """Write a guarded ``.npz`` file (:mod:`seds_casadi.core.model_files`: format, version,
        checksum; atomic; no pickle): ``ball``, ``hole`` [m], ``alpha_deg`` [deg], ``kappa``,
        ``labels`` and a JSON ``meta`` (field, strategy, dropped, stroke, situations)."""
        meta = {"field": self.field, "strategy": self.strategy, "dropped": int(self.dropped),
                "stroke": self.stroke.to_dict(), "situations": self.declared}
        write_guarded(path, DATASET_FORMAT, DATASET_VERSION,
                      {"ball": self.ball, "hole": self.hole, "alpha_deg": self.alpha_deg,
                       "kappa": self.kappa, "labels": np.asarray(self.labels, np.int64)}, meta)

    @classmethod
    def load(cls, path: str | os.PathLike) -> HittingDataset:
        """Read a file written by :meth:`save`: format, version and checksum are checked and
        the contents re-validated (shapes, finite values, positive speed gains, angles within
        +-180 deg, a valid stroke and strategy); anything wrong raises
        :class:`~seds_casadi.ModelFileError` naming the file and the entry."""
        path = os.fspath(path)
        a, meta, _ = read_guarded(path, DATASET_FORMAT, (DATASET_VERSION,), _SCHEMA)
        return cls.from_arrays(a, meta, path)


    @classmethod
    def from_arrays(cls, a: dict, meta: dict, source: str) -> HittingDataset:
        """A data set from the arrays and the meta of a saved file (``ball``, ``hole``,
        ``alpha_deg``, ``kappa``, ``labels``; ``field``, ``strategy``, ``dropped``, ``stroke``,
        ``situations`` as :meth:`save` writes them), re-validated; anything wrong raises
        :class:`~seds_casadi.ModelFileError` naming ``source`` (the file)."""
        n = len(a["alpha_deg"])
        if not (a["ball"].shape == a["hole"].shape == (n, 2) and a["kappa"].shape == (n,)
                and a["labels"].shape == (n,)):
            raise ModelFileError(f"{source}: not a hitting data set (arrays of different lengths)")
        if np.any(a["kappa"] <= 0) or np.any(np.abs(a["alpha_deg"]) > 180):
            raise ModelFileError(f"{source}: speed gains must be positive and angles within "
                                 "+-180 deg")
        if np.any(a["labels"] < 0):
            raise ModelFileError(f"{source}: entry 'labels' holds negative strategy labels")
        try:
            stroke = Stroke.from_dict(meta["stroke"])
            strategy, field_name = meta["strategy"], meta["field"]
            if strategy not in TEACHER_STRATEGIES or not isinstance(field_name, str):
                raise ValueError(f"unknown strategy {strategy!r} or field {field_name!r}")
            dropped = meta["dropped"]
            if not isinstance(dropped, int) or dropped < 0:
                raise ValueError(f"'dropped' must be a count, got {dropped!r}")
            declared = meta.get("situations", {})
            if not isinstance(declared, dict):
                raise ValueError("'situations' must be an object")
        except (KeyError, TypeError, ValueError) as exc:
            raise ModelFileError(f"{source}: entry 'meta' is not a valid hitting data set "
                                 f"({type(exc).__name__}: {exc})") from None
        return cls(field_name, strategy, a["ball"], a["hole"], np.deg2rad(a["alpha_deg"]),
                   a["kappa"], stroke, dropped, a["labels"], declared)
