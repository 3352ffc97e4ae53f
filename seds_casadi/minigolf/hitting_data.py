"""Good shots for a field: the teacher's situations (:func:`paper_situations`, drawn from the
field's declared situations) and the data set of the teacher's hitting parameters
(:class:`HittingDataset`, saved as ``.npz`` without pickle, the angle in degrees).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field

import numpy as np

from ..core._io import atomic_npz
from .fields import Field
from .stroke import Stroke

__all__ = ["HittingDataset", "paper_situations", "region_centre", "DATASET_VERSION"]

#: version of the ``.npz`` format written by :meth:`HittingDataset.save` (1: the angle in
#: radians under ``alpha``, read too; 2: ``alpha_deg``, strategy labels, the situations)
DATASET_VERSION = 2


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
        """Write an ``.npz`` file (atomic; no pickle): ``ball``, ``hole`` [m], ``alpha_deg``
        [deg], ``kappa``, ``labels`` and a JSON ``meta`` (version, field, strategy, dropped,
        stroke, situations)."""
        meta = {"version": DATASET_VERSION, "field": self.field, "strategy": self.strategy,
                "dropped": self.dropped, "stroke": self.stroke.to_dict(),
                "situations": self.declared}
        atomic_npz(path, ball=self.ball, hole=self.hole, alpha_deg=self.alpha_deg,
                   kappa=self.kappa, labels=self.labels, meta=np.array(json.dumps(meta)))

    @classmethod
    def load(cls, path: str | os.PathLike) -> HittingDataset:
        """Read a file written by :meth:`save` (also version 1, with the angle in radians)."""
        try:
            with np.load(path, allow_pickle=False) as z:
                meta = json.loads(str(z["meta"]))
                version = int(meta.get("version", 1))
                if version > DATASET_VERSION:
                    raise ValueError(f"version {version} is newer than this library's "
                                     f"({DATASET_VERSION})")
                alpha = np.deg2rad(z["alpha_deg"]) if version >= 2 else z["alpha"]
                labels = z["labels"] if "labels" in z else None
                st = meta["stroke"]
                out = cls(meta["field"], meta["strategy"], z["ball"], z["hole"], alpha,
                          z["kappa"], Stroke(np.array(st["direction"]), st["speed"],
                                             st["club_mass"], st["restitution"]),
                          int(meta["dropped"]), labels, meta.get("situations", {}))
        except (OSError, KeyError, ValueError, TypeError) as exc:
            raise ValueError(f"{path}: not a hitting data set ({exc})") from None
        n = len(out.alpha)
        if not (out.ball.shape == out.hole.shape == (n, 2) and out.kappa.shape == (n,)
                and out.labels.shape == (n,)):
            raise ValueError(f"{path}: not a hitting data set (arrays of different lengths)")
        return out
