"""Good shots for a field: the paper's situations (:func:`paper_situations`) and the data set
of the teacher's hitting parameters (:class:`HittingDataset`, saved as ``.npz`` without pickle).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass

import numpy as np

from ..core._io import atomic_npz
from .fields import Field
from .stroke import Stroke

__all__ = ["HittingDataset", "paper_situations", "region_centre"]


def region_centre(region) -> np.ndarray:
    """The centre (x, y) of a box [xmin, xmax, ymin, ymax]."""
    return np.array([(region[0] + region[1]) / 2, (region[2] + region[3]) / 2])


def paper_situations(field: Field, layout: str | None = None, n: int | None = None):
    """The paper's situations for a field: balls and holes, each shape (n, 2).

    ``layout="line"`` (default except on arctan): the ball at the centre of the ball region,
    the hole moved sideways along the far edge (the field's hole x, y across the field),
    ``n`` = 20. ``layout="grid"`` (arctan): the hole at its place, the ball on a 7 x 8 grid over
    the ball region, ``n`` = 56 (or the nearest grid to ``n``).
    """
    if layout is None:
        layout = "grid" if field.surface.shape == "arctan" else "line"
    b, R = field.bounds, field.hole_radius
    if layout == "line":
        n = 20 if n is None else int(n)
        margin = 0.15 * (b[3] - b[2])
        ys = np.linspace(b[2] + margin, b[3] - margin, n)
        holes = np.column_stack([np.full(n, field.hole[0]), ys])
        balls = np.tile(region_centre(field.ball_region), (n, 1))
        assert np.all(np.abs(ys) <= b[3] - R)
        return balls, holes
    if layout == "grid":
        n = 56 if n is None else int(n)
        nx = max(2, int(round(np.sqrt(n * 7 / 8))))
        ny = max(2, int(round(n / nx)))
        r = field.ball_region
        X, Y = np.meshgrid(np.linspace(r[0], r[1], nx), np.linspace(r[2], r[3], ny),
                           indexing="ij")
        balls = np.column_stack([X.ravel(), Y.ravel()])
        return balls, np.tile(field.hole, (len(balls), 1))
    raise ValueError(f"layout must be 'line' or 'grid', got {layout!r}")


@dataclass
class HittingDataset:
    """Good shots for a field: situations and the teacher's (alpha, kappa).

    Attributes
    ----------
    field : str
    strategy : str
    ball, hole : array, shape (n, 2)
    alpha : array, shape (n,)
        Hitting angles [rad].
    kappa : array, shape (n,)
    stroke : Stroke
    dropped : int
        Situations where the strategy found no successful hit.
    """

    field: str
    strategy: str
    ball: np.ndarray
    hole: np.ndarray
    alpha: np.ndarray
    kappa: np.ndarray
    stroke: Stroke
    dropped: int = 0

    def __len__(self) -> int:
        return len(self.alpha)

    @property
    def situations(self) -> np.ndarray:
        """s = hole - ball, shape (n, 2)."""
        return self.hole - self.ball

    @property
    def outputs(self) -> np.ndarray:
        """What the learners predict: alpha [deg] for fixed speed, (alpha [deg], kappa) else."""
        a = np.rad2deg(self.alpha)
        return a[:, None] if self.strategy == "fixed_speed" else np.column_stack([a, self.kappa])

    def save(self, path: str | os.PathLike) -> None:
        """Write an ``.npz`` file (atomic; no pickle)."""
        atomic_npz(path, ball=self.ball, hole=self.hole, alpha=self.alpha, kappa=self.kappa,
                   meta=np.array(json.dumps({"field": self.field, "strategy": self.strategy,
                                             "dropped": self.dropped,
                                             "stroke": self.stroke.to_dict()})))

    @classmethod
    def load(cls, path: str | os.PathLike) -> HittingDataset:
        """Read a file written by :meth:`save`."""
        try:
            with np.load(path, allow_pickle=False) as z:
                meta = json.loads(str(z["meta"]))
                st = meta["stroke"]
                return cls(meta["field"], meta["strategy"], z["ball"], z["hole"], z["alpha"],
                           z["kappa"], Stroke(np.array(st["direction"]), st["speed"],
                                              st["club_mass"], st["restitution"]),
                           int(meta["dropped"]))
        except (OSError, KeyError, ValueError) as exc:
            raise ValueError(f"{path}: not a hitting data set ({exc})") from None
