"""The situations a field declares: where the ball may lie and where the hole may be.

The paper's situation (Section 3, Eq. 2) is s = hole - ball, the hole's position relative to
the ball in the field's plane. A field file says which situations are played with an entry
``"situations"`` (format in :mod:`seds_casadi.minigolf.fields`)::

    "situations": {"ball": {"fixed": [0.1, 0.0]},
                   "hole": {"slider": [[2.4, -0.42], [2.4, 0.42]]}}

Each of ``ball`` and ``hole`` is a :class:`Placement`: a fixed point (``{"fixed": [x, y]}``),
a slider, the segment between two points (``{"slider": [[x0, y0], [x1, y1]]}``, the paper's
hole moved along the edge of the field, Fig. 9 and 12), or a region
(``{"region": [xmin, xmax, ymin, ymax]}``). Without the entry (older files) the ball may lie
anywhere in the field's ``ball_region`` and the hole is the field's ``hole``; a missing
``ball`` or ``hole`` inside the entry takes the same default.

One declaration serves everything that draws situations: the teacher's data set
(:meth:`Situations.design`: 20 equally spaced situations along a one-dimensional situation
space, a grid of 56 over a two-dimensional one, the paper's sizes), the test situations of
Table 1 and the situations of ``play`` and ``validate`` (:meth:`Situations.sample`, uniform).

The learners see s only. When both the ball and the hole move, s does not say where on the
field the shot is played, which matters on any surface but a plane; such declarations are
refused on other surfaces (fix one of the two).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..motion.golf import BALL_RADIUS

#: the kinds of placement a field file may declare for the ball and the hole
PLACEMENT_KINDS = ("fixed", "slider", "region")
#: the teacher's number of situations by the dimension of the situation space (the paper's
#: data sets: 20 along the slider of the rough flat and double hill fields, 56 on arctan)
DEFAULT_EXAMPLES = {1: 20, 2: 56}


def grid_shape(n: int, width: float, height: float) -> tuple[int, int]:
    """Columns along x and rows along y of a grid of about ``n`` points over a box: the most
    nearly square pair (round(sqrt(n)), ceil(n / round(sqrt(n)))), the larger count along the
    longer side (56 points over the arctan ball region: 7 along x, 8 along y)."""
    a = max(1, int(round(np.sqrt(n))))
    b = max(1, int(np.ceil(n / a)))
    small, large = min(a, b), max(a, b)
    return (large, small) if width > height else (small, large)


@dataclass(frozen=True)
class Placement:
    """Where the ball or the hole may be.

    Attributes
    ----------
    kind : {"fixed", "slider", "region"}
    points : array, shape (2, 2) or (1, 2)
        ``fixed``: the point (1, 2); ``slider``: its two ends (2, 2); ``region``: its corners
        [[xmin, ymin], [xmax, ymax]].
    """

    kind: str
    points: np.ndarray

    @classmethod
    def from_spec(cls, spec, where: str) -> Placement:
        """A placement from its file entry (``{"fixed": ...}``, ``{"slider": ...}`` or
        ``{"region": ...}``); errors name the entry ``where``."""
        if not isinstance(spec, dict) or len(spec) != 1 or next(iter(spec)) not in PLACEMENT_KINDS:
            raise ValueError(f"{where}: one of {{\"fixed\": [x, y]}}, {{\"slider\": [[x0, y0], "
                             f"[x1, y1]]}} or {{\"region\": [xmin, xmax, ymin, ymax]}} is "
                             f"needed, got {spec!r}")
        kind, v = next(iter(spec.items()))
        try:
            a = np.asarray(v, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"{where}.{kind}: numbers needed, got {v!r}") from None
        shapes = {"fixed": (2,), "slider": (2, 2), "region": (4,)}
        if a.shape != shapes[kind] or not np.all(np.isfinite(a)):
            form = {"fixed": "[x, y]", "slider": "[[x0, y0], [x1, y1]]",
                    "region": "[xmin, xmax, ymin, ymax]"}[kind]
            raise ValueError(f"{where}.{kind}: {form} of finite numbers needed, got {v!r}")
        if kind == "fixed":
            return cls(kind, a[None, :])
        if kind == "slider":
            if np.linalg.norm(a[1] - a[0]) < 1e-9:
                raise ValueError(f"{where}.slider: its two ends are the same point; use "
                                 f"{{\"fixed\": {a[0].tolist()}}} for a fixed position")
            return cls(kind, a)
        if not (a[0] < a[1] and a[2] < a[3]):
            raise ValueError(f"{where}.region: [xmin, xmax, ymin, ymax] with min < max needed, "
                             f"got {v!r}")
        return cls(kind, np.array([[a[0], a[2]], [a[1], a[3]]]))

    def to_spec(self) -> dict:
        """The file entry of this placement."""
        if self.kind == "fixed":
            return {"fixed": self.points[0].tolist()}
        if self.kind == "slider":
            return {"slider": self.points.tolist()}
        (x0, y0), (x1, y1) = self.points
        return {"region": [float(x0), float(x1), float(y0), float(y1)]}

    @property
    def directions(self) -> np.ndarray:
        """Directions in which the placement extends, shape (0, 1 or 2, 2)."""
        if self.kind == "fixed":
            return np.zeros((0, 2))
        if self.kind == "slider":
            d = self.points[1] - self.points[0]
            return (d / np.linalg.norm(d))[None]
        return np.eye(2)

    @property
    def box(self) -> np.ndarray:
        """[xmin, xmax, ymin, ymax] of the points the placement covers."""
        lo, hi = self.points.min(axis=0), self.points.max(axis=0)
        return np.array([lo[0], hi[0], lo[1], hi[1]])

    def design(self, n: int) -> np.ndarray:
        """About ``n`` evenly spread positions, shape (m, 2): the point (m = 1), ``n``
        equally spaced points from one end of the slider to the other, or a grid over the
        region (:func:`grid_shape`, rows of equal x first)."""
        n = max(1, int(n))
        if self.kind == "fixed":
            return self.points.copy()
        if self.kind == "slider":
            t = np.linspace(0.0, 1.0, n)[:, None]
            return self.points[0] + t * (self.points[1] - self.points[0])
        (x0, y0), (x1, y1) = self.points
        nx, ny = grid_shape(n, x1 - x0, y1 - y0)
        X, Y = np.meshgrid(np.linspace(x0, x1, nx), np.linspace(y0, y1, ny), indexing="ij")
        return np.column_stack([X.ravel(), Y.ravel()])

    def sample(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """``n`` positions drawn uniformly from the placement, shape (n, 2)."""
        if self.kind == "fixed":
            return np.tile(self.points[0], (n, 1))
        if self.kind == "slider":
            t = rng.uniform(size=(n, 1))
            return self.points[0] + t * (self.points[1] - self.points[0])
        lo, hi = self.points
        return lo + rng.uniform(size=(n, 2)) * (hi - lo)

    def describe(self) -> str:
        """In words, for messages."""
        p = np.round(self.points, 3).tolist()
        if self.kind == "fixed":
            return f"fixed at {p[0]}"
        if self.kind == "slider":
            return f"on the slider from {p[0]} to {p[1]}"
        return f"in the region x {p[0][0]}..{p[1][0]}, y {p[0][1]}..{p[1][1]}"


@dataclass(frozen=True)
class Situations:
    """The situations a field declares: a :class:`Placement` of the ball and one of the hole.

    Attributes
    ----------
    ball, hole : Placement
    declared : bool
        False when the field file has no ``"situations"`` entry (the documented default).
    """

    ball: Placement
    hole: Placement
    declared: bool = True

    @classmethod
    def from_spec(cls, spec, field_hole, ball_region, bounds, hole_radius: float,
                  surface_shape: str, source: str = "field") -> Situations:
        """Validate a ``"situations"`` entry (None: the default) against the field.

        Parameters
        ----------
        spec : dict or None
        field_hole : array, shape (2,)
            The field's ``hole`` (the default hole placement).
        ball_region, bounds : array, shape (4,)
            The field's ball region (the default ball placement, and where a declared ball
            placement must lie) and its bounds (where the hole must lie, one radius inside).
        hole_radius : float
        surface_shape : str
            Declarations that move both the ball and the hole need a plane.
        """
        where = f"{source}: situations"
        if spec is None:
            spec, declared = {}, False
        else:
            declared = True
            if not isinstance(spec, dict):
                raise ValueError(f"{where}: an object with entries 'ball' and/or 'hole' is "
                                 f"needed, got {spec!r}")
            unknown = sorted(set(spec) - {"ball", "hole"})
            if unknown:
                raise ValueError(f"{where}: unknown entry {unknown[0]!r}; valid: ball, hole")
        r = np.asarray(ball_region, float)
        ball = (Placement.from_spec(spec["ball"], f"{where}.ball") if "ball" in spec
                else Placement("region", np.array([[r[0], r[2]], [r[1], r[3]]])))
        hole = (Placement.from_spec(spec["hole"], f"{where}.hole") if "hole" in spec
                else Placement("fixed", np.asarray(field_hole, float)[None, :]))
        out = cls(ball, hole, declared)
        out._check(r, np.asarray(bounds, float), float(hole_radius), surface_shape, where)
        return out

    def _check(self, region, bounds, radius, shape, where) -> None:
        bb, hb = self.ball.box, self.hole.box
        if not (region[0] - 1e-9 <= bb[0] and bb[1] <= region[1] + 1e-9
                and region[2] - 1e-9 <= bb[2] and bb[3] <= region[3] + 1e-9):
            raise ValueError(f"{where}.ball: the ball {self.ball.describe()} leaves the field's "
                             f"ball_region {region.tolist()}; move it inside or enlarge the "
                             f"ball_region")
        inner = bounds + np.array([radius, -radius, radius, -radius])
        if not (inner[0] - 1e-9 <= hb[0] and hb[1] <= inner[1] + 1e-9
                and inner[2] - 1e-9 <= hb[2] and hb[3] <= inner[3] + 1e-9):
            raise ValueError(f"{where}.hole: the hole {self.hole.describe()} is not inside the "
                             f"field's bounds {bounds.tolist()} by its radius {radius}; keep "
                             f"it within x {inner[0]:.3f}..{inner[1]:.3f}, y "
                             f"{inner[2]:.3f}..{inner[3]:.3f}")
        if self.dim == 0:
            raise ValueError(f"{where}: the ball and the hole are both fixed, which is a single "
                             f"situation; let one of them move (a 'slider' or a 'region')")
        if self.ball.kind != "fixed" and self.hole.kind != "fixed" and shape != "plane":
            raise ValueError(f"{where}: both the ball and the hole move, but the learners see "
                             f"only s = hole - ball, which on a {shape!r} surface does not say "
                             f"where the shot is played; fix one of them (or use a plane)")
        B, H = self.ball.design(400), self.hole.design(400)
        d2 = np.sum((B[:, None, :] - H[None, :, :]) ** 2, axis=2)
        i, j = np.unravel_index(np.argmin(d2), d2.shape)
        if np.sqrt(d2[i, j]) <= radius + BALL_RADIUS:
            raise ValueError(f"{where}: a ball at {np.round(B[i], 3).tolist()} would lie in the "
                             f"hole at {np.round(H[j], 3).tolist()}; keep the ball's and the "
                             f"hole's placements at least {radius + BALL_RADIUS:.3f} m apart")

    @property
    def dim(self) -> int:
        """Dimension of the situation space (of s = hole - ball): 1 or 2."""
        D = np.concatenate([self.ball.directions, self.hole.directions])
        return int(np.linalg.matrix_rank(D, tol=1e-9)) if len(D) else 0

    @property
    def default_examples(self) -> int:
        """The teacher's number of situations by default (:data:`DEFAULT_EXAMPLES`)."""
        return DEFAULT_EXAMPLES[min(max(self.dim, 1), 2)]

    def to_spec(self) -> dict:
        """The ``"situations"`` entry of a field file."""
        return {"ball": self.ball.to_spec(), "hole": self.hole.to_spec()}

    def design(self, n: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The teacher's situations: balls and holes, each shape (m, 2).

        ``n`` (default :attr:`default_examples`) evenly spread over the declared space: along
        the one placement that moves (its :meth:`Placement.design`), or, when both move, the
        combinations of about sqrt(n) balls and sqrt(n) holes.
        """
        n = self.default_examples if n is None else int(n)
        if n < 2:
            raise ValueError(f"the teacher needs at least 2 situations, got {n}")
        if self.hole.kind == "fixed":
            balls = self.ball.design(n)
            return balls, np.tile(self.hole.points[0], (len(balls), 1))
        if self.ball.kind == "fixed":
            holes = self.hole.design(n)
            return np.tile(self.ball.points[0], (len(holes), 1)), holes
        nb = max(2, int(round(np.sqrt(n))))
        B, H = self.ball.design(nb), self.hole.design(int(np.ceil(n / nb)))
        return np.repeat(B, len(H), axis=0), np.tile(H, (len(B), 1))

    def sample(self, n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """``n`` random situations (balls, holes; each (n, 2)), uniform over the declaration."""
        n = int(n)
        return self.ball.sample(n, rng), self.hole.sample(n, rng)

    def describe(self) -> str:
        """In words, for messages and reports."""
        default = "" if self.declared else " (the default: no 'situations' in the file)"
        return f"ball {self.ball.describe()}, hole {self.hole.describe()}{default}"
