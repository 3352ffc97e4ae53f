"""Minigolf fields: a surface z = H(x, y), a boundary, a hole, a ball region and a surface speed.

A field is one JSON file (``fields/*.json``; copy one to make your own)::

    {
      "name": "double_hill",
      "surface": {"shape": "hills", "hills": [{"x": 1.0, "y": 0.3, "height": 0.04,
                                               "width": 0.25}, ...]},
      "bounds": [xmin, xmax, ymin, ymax],        # metres; the playing area
      "boundary": "walls",                       # "walls" (bounce) or "edges" (ball is lost)
      "wall_restitution": 0.6,                   # walls only
      "hole": {"x": 2.5, "y": 0.0, "radius": 0.054},
      "ball_region": [xmin, xmax, ymin, ymax],   # where the ball may lie before a shot
      "stimp": 10                                # surface speed (Stimpmeter, feet), or
      "rolling_resistance": 0.0785               # rho directly (deceleration (5/7) rho g)
    }

Surface shapes (``"shape"`` and its parameters):

* ``"plane"``: ``slope_x``, ``slope_y`` (dz/dx, dz/dy; 0 and 0 for the flat field);
* ``"hills"``: ``hills``, a list of Gaussian hills ``height * exp(-|p - c|^2 / (2 width^2))``;
* ``"arctan"``: ``height * arctan(steepness * (y - y0)) / (pi/2)`` over the field, the paper's
  "scaled evaluation of the arctan function over a grid": a cross slope that bends the ball's path
  (``axis`` "y" or "x" chooses the direction it rises along);
* ``"rough"``: ``bumps`` random Gaussian bumps of ``amplitude`` and ``width`` (seeded by ``seed``),
  plus ``friction_variation``, the relative amplitude of a smooth random variation of the rolling
  resistance: small irregularities that scatter shots (the paper's rough flat field);
* ``"heightmap"``: ``extent`` [xmin, xmax, ymin, ymax] and ``heights`` (rows along y, columns
  along x), interpolated by a bicubic spline.

Rolling resistance by Stimpmeter reading (Penner, "The Physics of Putting", 2002): 6 -> 0.131,
8 -> 0.0985, 10 -> 0.0785, 12 -> 0.0655 (interpolated linearly in between).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from ..core._io import data_folder

__all__ = ["Field", "Surface", "load_field", "field_names", "FIELDS_FOLDER", "stimp_to_rho"]

#: folder of the shipped field files (the repository's ``fields/``, installed as package data)
FIELDS_FOLDER = data_folder("seds_casadi._fields")
_STIMP = np.array([[6.0, 0.131], [8.0, 0.0985], [10.0, 0.0785], [12.0, 0.0655]])
_SHAPES = ("plane", "hills", "arctan", "rough", "heightmap")


def stimp_to_rho(stimp: float) -> float:
    """Rolling-resistance coefficient rho for a Stimpmeter reading (feet), 6 to 12."""
    s = float(stimp)
    if not 6.0 <= s <= 12.0:
        raise ValueError(f"stimp must be between 6 and 12 (feet), got {stimp}")
    return float(np.interp(s, _STIMP[:, 0], _STIMP[:, 1]))


class Surface:
    """z = H(x, y) with its gradient and Hessian, vectorised.

    Build with :meth:`from_spec`; call ``height(P)``, ``gradient(P)``, ``hessian(P)`` with P of
    shape (n, 2).
    """

    def __init__(self, shape: str, params: dict) -> None:
        self.shape = shape
        self.params = params
        self._friction = None
        if shape == "rough":
            rng = np.random.default_rng(int(params.get("seed", 0)))
            b = params["_bounds"]
            n = int(params["bumps"])
            self._c = np.column_stack([rng.uniform(b[0], b[1], n), rng.uniform(b[2], b[3], n)])
            self._a = float(params["amplitude"]) * rng.uniform(-1, 1, n)
            self._w = np.full(n, float(params["width"]))
            fv = float(params.get("friction_variation", 0.0))
            if fv:
                m = max(4, n // 4)
                fc = np.column_stack([rng.uniform(b[0], b[1], m), rng.uniform(b[2], b[3], m)])
                fa = fv * rng.uniform(-1, 1, m)
                fw = 3 * float(params["width"])
                self._friction = (fc, fa, fw)
        elif shape == "hills":
            hills = params["hills"]
            self._c = np.array([[h["x"], h["y"]] for h in hills], dtype=float).reshape(-1, 2)
            self._a = np.array([h["height"] for h in hills], dtype=float)
            self._w = np.array([h["width"] for h in hills], dtype=float)
        elif shape == "heightmap":
            from scipy.interpolate import RectBivariateSpline

            ext = params["extent"]
            Z = np.asarray(params["heights"], dtype=float)
            xs = np.linspace(ext[0], ext[1], Z.shape[1])
            ys = np.linspace(ext[2], ext[3], Z.shape[0])
            self._spline = RectBivariateSpline(xs, ys, Z.T, kx=3, ky=3)

    @classmethod
    def from_spec(cls, spec: dict, bounds, where: str = "surface") -> Surface:
        """Validate a surface specification (see the module docstring) and build it."""
        if not isinstance(spec, dict) or "shape" not in spec:
            raise ValueError(f"{where}: needs an entry 'shape' (one of {', '.join(_SHAPES)})")
        shape = spec["shape"]
        if shape not in _SHAPES:
            raise ValueError(f"{where}.shape: unknown shape {shape!r}; valid: {', '.join(_SHAPES)}")
        p = dict(spec)

        def num(key, positive=False, default=None):
            if key not in p:
                if default is None:
                    raise ValueError(f"{where}: missing entry {key!r} for shape {shape!r}")
                p[key] = default
            try:
                v = float(p[key])
            except (TypeError, ValueError):
                raise ValueError(f"{where}.{key}: not a number: {p[key]!r}") from None
            if not np.isfinite(v) or (positive and v <= 0):
                raise ValueError(f"{where}.{key}: must be {'positive' if positive else 'finite'},"
                                 f" got {p[key]!r}")
            return v

        if shape == "plane":
            num("slope_x", default=0.0)
            num("slope_y", default=0.0)
        elif shape == "hills":
            hills = p.get("hills")
            if not isinstance(hills, list) or not hills:
                raise ValueError(f"{where}.hills: a non-empty list of hills is needed")
            for i, h in enumerate(hills):
                for k in ("x", "y", "height", "width"):
                    if k not in h:
                        raise ValueError(f"{where}.hills[{i}]: missing entry {k!r}")
                    if not np.isfinite(float(h[k])):
                        raise ValueError(f"{where}.hills[{i}].{k}: must be finite")
                if float(h["width"]) <= 0:
                    raise ValueError(f"{where}.hills[{i}].width: must be positive")
        elif shape == "arctan":
            num("height")
            num("steepness", positive=True)
            num("y0", default=0.0)
            if p.get("axis", "y") not in ("x", "y"):
                raise ValueError(f"{where}.axis: 'x' or 'y', got {p.get('axis')!r}")
        elif shape == "rough":
            num("amplitude")
            num("width", positive=True)
            num("bumps", positive=True)
            num("friction_variation", default=0.0)
            if not 0 <= float(p["friction_variation"]) < 1:
                raise ValueError(f"{where}.friction_variation: must be in [0, 1)")
            p["_bounds"] = bounds
        elif shape == "heightmap":
            ext = p.get("extent")
            if ext is None or len(ext) != 4 or not (ext[0] < ext[1] and ext[2] < ext[3]):
                raise ValueError(f"{where}.extent: [xmin, xmax, ymin, ymax] with min < max needed")
            Z = np.asarray(p.get("heights", []), dtype=float)
            if Z.ndim != 2 or min(Z.shape) < 4:
                raise ValueError(f"{where}.heights: a 2-D grid of at least 4 x 4 heights (rows "
                                 f"along y, columns along x) is needed, got shape {Z.shape}")
            if not np.all(np.isfinite(Z)):
                raise ValueError(f"{where}.heights: contains NaN or infinite values")
            if (ext[0] > bounds[0] or ext[1] < bounds[1] or ext[2] > bounds[2]
                    or ext[3] < bounds[3]):
                raise ValueError(f"{where}.extent {ext} does not cover the field's bounds {bounds}")
        return cls(shape, p)

    # ---------------------------------------------------------------- evaluation
    def _gauss(self, P):
        d = P[:, None, :] - self._c[None]
        g = self._a * np.exp(-np.sum(d * d, axis=2) / (2 * self._w**2))
        return d, g

    def height(self, P: np.ndarray) -> np.ndarray:
        """H at points P, shape (n, 2) -> (n,)."""
        P = np.atleast_2d(P)
        s, p = self.shape, self.params
        if s == "plane":
            return p["slope_x"] * P[:, 0] + p["slope_y"] * P[:, 1]
        if s in ("hills", "rough"):
            return self._gauss(P)[1].sum(axis=1)
        if s == "arctan":
            u = P[:, 1] if p.get("axis", "y") == "y" else P[:, 0]
            return p["height"] * np.arctan(p["steepness"] * (u - p["y0"])) / (np.pi / 2)
        return self._spline.ev(P[:, 0], P[:, 1])

    def gradient(self, P: np.ndarray) -> np.ndarray:
        """(dH/dx, dH/dy) at P, shape (n, 2)."""
        P = np.atleast_2d(P)
        s, p = self.shape, self.params
        if s == "plane":
            return np.tile([p["slope_x"], p["slope_y"]], (len(P), 1))
        if s in ("hills", "rough"):
            d, g = self._gauss(P)
            return -np.einsum("nk,nkj->nj", g / self._w**2, d)
        if s == "arctan":
            u = P[:, 1] if p.get("axis", "y") == "y" else P[:, 0]
            k = p["steepness"]
            du = p["height"] * k / (1 + (k * (u - p["y0"])) ** 2) / (np.pi / 2)
            out = np.zeros((len(P), 2))
            out[:, 1 if p.get("axis", "y") == "y" else 0] = du
            return out
        return np.column_stack([self._spline.ev(P[:, 0], P[:, 1], dx=1),
                                self._spline.ev(P[:, 0], P[:, 1], dy=1)])

    def hessian(self, P: np.ndarray) -> np.ndarray:
        """Second derivatives of H at P, shape (n, 2, 2)."""
        P = np.atleast_2d(P)
        s, p = self.shape, self.params
        out = np.zeros((len(P), 2, 2))
        if s == "plane":
            return out
        if s in ("hills", "rough"):
            d, g = self._gauss(P)
            w2 = self._w**2
            out = np.einsum("nk,nki,nkj->nij", g / w2**2, d, d)
            out -= np.einsum("nk,ij->nij", g / w2, np.eye(2))
            return out
        if s == "arctan":
            axis = 1 if p.get("axis", "y") == "y" else 0
            u = P[:, axis]
            k = p["steepness"]
            z = k * (u - p["y0"])
            out[:, axis, axis] = -p["height"] * 2 * k * k * z / (1 + z * z) ** 2 / (np.pi / 2)
            return out
        sp = self._spline
        out[:, 0, 0] = sp.ev(P[:, 0], P[:, 1], dx=2)
        out[:, 1, 1] = sp.ev(P[:, 0], P[:, 1], dy=2)
        out[:, 0, 1] = out[:, 1, 0] = sp.ev(P[:, 0], P[:, 1], dx=1, dy=1)
        return out

    # ---------------------------------------------------------------- symbolic form
    @property
    def tabulated(self) -> bool:
        """Whether :meth:`casadi_terms` reads the derivatives from a table (see :meth:`table`)."""
        return self.shape in ("rough", "heightmap")

    def table(self, bounds, spacing: float = 0.01) -> tuple[list[np.ndarray], np.ndarray]:
        """Grid and values of (dH/dx, dH/dy, H_xx, H_xy, H_yy, friction factor) over ``bounds``.

        Used by the compiled ball model for surfaces whose exact evaluation is expensive (many
        bumps, splines); the values are interpolated linearly between grid points.

        Returns
        -------
        grid : [xs, ys]
        values : array, shape (6 * len(xs) * len(ys),)
            Flattened in CasADi's interpolant order (channel fastest, then x, then y).
        """
        b = np.asarray(bounds, dtype=float)
        xs = np.linspace(b[0], b[1], max(4, int(np.ceil((b[1] - b[0]) / spacing)) + 1))
        ys = np.linspace(b[2], b[3], max(4, int(np.ceil((b[3] - b[2]) / spacing)) + 1))
        X, Y = np.meshgrid(xs, ys, indexing="ij")
        P = np.column_stack([X.ravel(order="F"), Y.ravel(order="F")])
        g, h = self.gradient(P), self.hessian(P)
        vals = np.column_stack([g[:, 0], g[:, 1], h[:, 0, 0], h[:, 0, 1], h[:, 1, 1],
                                self.friction_factor(P)])
        return [xs, ys], vals.ravel()

    def casadi_terms(self, p, bounds=None, spacing: float = 0.01):
        """Gradient (2,), Hessian (2, 2) and friction factor of H at the point ``p`` in CasADi.

        Analytic for "plane", "hills" and "arctan" (the same formulas as :meth:`gradient` and
        :meth:`hessian`); for tabulated shapes, a linear interpolation of :meth:`table` over
        ``bounds`` (the table is embedded in the expression as constants).
        """
        s, prm = self.shape, self.params
        if self.tabulated:
            if bounds is None:
                raise ValueError(f"a {s!r} surface is tabulated: give the bounds to cover")
            grid, values = self.table(bounds, spacing)
            v = ca.interpolant("surface_table", "linear", grid, values)(p)
            hess = ca.vertcat(ca.horzcat(v[2], v[3]), ca.horzcat(v[3], v[4]))
            return v[0:2], hess, v[5]
        hess = ca.SX.zeros(2, 2) if isinstance(p, ca.SX) else ca.MX.zeros(2, 2)
        if s == "plane":
            return ca.vertcat(prm["slope_x"], prm["slope_y"]) + 0 * p, hess, 1.0
        if s == "hills":
            grad = 0 * p
            for c, a, w in zip(self._c, self._a, self._w):
                d = p - c
                gk = a * ca.exp(-ca.dot(d, d) / (2 * w**2))
                grad = grad - gk / w**2 * d
                hess = hess + gk / w**4 * ca.mtimes(d, d.T) - gk / w**2 * ca.DM.eye(2)
            return grad, hess, 1.0
        axis = 1 if prm.get("axis", "y") == "y" else 0
        k = prm["steepness"]
        z = k * (p[axis] - prm["y0"])
        du = prm["height"] * k / (1 + z * z) / (np.pi / 2)
        duu = -prm["height"] * 2 * k * k * z / (1 + z * z) ** 2 / (np.pi / 2)
        grad = ca.vertcat(0, du) if axis == 1 else ca.vertcat(du, 0)
        hess[axis, axis] = duu
        return grad, hess, 1.0

    def friction_factor(self, P: np.ndarray) -> np.ndarray:
        """Multiplier of the rolling resistance at P (1 except on fields with variation)."""
        P = np.atleast_2d(P)
        if self._friction is None:
            return np.ones(len(P))
        fc, fa, fw = self._friction
        d = P[:, None, :] - fc[None]
        return 1.0 + np.sum(fa * np.exp(-np.sum(d * d, axis=2) / (2 * fw**2)), axis=1)


@dataclass
class Field:
    """A minigolf field (see the module docstring for the file format).

    Attributes
    ----------
    name : str
    surface : Surface
    bounds : array, shape (4,)
        [xmin, xmax, ymin, ymax] of the playing area [m].
    boundary : {"walls", "edges"}
    wall_restitution : float
    hole : array, shape (2,)
    hole_radius : float
    ball_region : array, shape (4,)
    rolling_resistance : float
        rho; a rolling ball decelerates by (5/7) rho g.
    """

    name: str
    surface: Surface
    bounds: np.ndarray
    boundary: str
    hole: np.ndarray
    hole_radius: float
    ball_region: np.ndarray
    rolling_resistance: float
    wall_restitution: float = 0.6
    spec: dict = field(default_factory=dict, repr=False)

    @classmethod
    def from_dict(cls, spec: dict, source: str = "field") -> Field:
        """Validate a field specification and build the field; errors name the entry."""
        if not isinstance(spec, dict):
            raise ValueError(f"{source}: a field is a JSON object, got {type(spec).__name__}")
        for key in ("name", "surface", "bounds", "hole", "ball_region"):
            if key not in spec:
                raise ValueError(f"{source}: missing entry {key!r}")
        bounds = _box(spec["bounds"], f"{source}: bounds")
        region = _box(spec["ball_region"], f"{source}: ball_region")
        if not (bounds[0] <= region[0] and region[1] <= bounds[1] and bounds[2] <= region[2]
                and region[3] <= bounds[3]):
            raise ValueError(f"{source}: ball_region {list(region)} is not inside the bounds "
                             f"{list(bounds)}")
        boundary = spec.get("boundary", "walls")
        if boundary not in ("walls", "edges"):
            raise ValueError(f"{source}: boundary must be 'walls' or 'edges', got {boundary!r}")
        hole = spec["hole"]
        try:
            hxy = np.array([float(hole["x"]), float(hole["y"])])
            hr = float(hole.get("radius", 0.054))
        except (KeyError, TypeError, ValueError):
            raise ValueError(f"{source}: hole needs numbers x, y (and radius)") from None
        if not (np.all(np.isfinite(hxy)) and np.isfinite(hr) and hr > 0):
            raise ValueError(f"{source}: hole position and radius must be finite, radius > 0")
        if not (bounds[0] + hr <= hxy[0] <= bounds[1] - hr
                and bounds[2] + hr <= hxy[1] <= bounds[3] - hr):
            raise ValueError(f"{source}: hole at {list(hxy)} is outside the field {list(bounds)}")
        if "rolling_resistance" in spec:
            rho = float(spec["rolling_resistance"])
            if not (np.isfinite(rho) and rho >= 0):
                raise ValueError(f"{source}: rolling_resistance must be >= 0, got {rho}")
        elif "stimp" in spec:
            rho = stimp_to_rho(spec["stimp"])
        else:
            raise ValueError(f"{source}: missing entry 'stimp' or 'rolling_resistance'")
        e = float(spec.get("wall_restitution", 0.6))
        if not 0 <= e <= 1:
            raise ValueError(f"{source}: wall_restitution must be in [0, 1], got {e}")
        surface = Surface.from_spec(spec["surface"], list(bounds), f"{source}: surface")
        return cls(str(spec["name"]), surface, bounds, boundary, hxy, hr, region, rho, e, spec)

    def check_situation(self, ball_xy) -> np.ndarray:
        """Validate ball positions (n, 2) against the ball region; returns them as an array."""
        B = np.atleast_2d(np.asarray(ball_xy, dtype=float))
        if B.shape[1] != 2 or not np.all(np.isfinite(B)):
            raise ValueError(f"ball positions must be finite, shape (n, 2); got {B.shape}")
        r = self.ball_region
        bad = ~((r[0] <= B[:, 0]) & (B[:, 0] <= r[1]) & (r[2] <= B[:, 1]) & (B[:, 1] <= r[3]))
        if bad.any():
            raise ValueError(f"ball position {list(B[np.argmax(bad)])} is outside the field's "
                             f"ball region {list(r)}")
        return B


def _box(v, what) -> np.ndarray:
    try:
        b = np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{what}: [xmin, xmax, ymin, ymax] of numbers needed") from None
    if b.shape != (4,) or not np.all(np.isfinite(b)) or not (b[0] < b[1] and b[2] < b[3]):
        raise ValueError(f"{what}: [xmin, xmax, ymin, ymax] with min < max needed, got {v!r}")
    return b


def field_names() -> list[str]:
    """Names of the fields shipped with the package."""
    if not os.path.isdir(FIELDS_FOLDER):
        return []
    return sorted(f[:-5] for f in os.listdir(FIELDS_FOLDER) if f.endswith(".json"))


def load_field(name_or_path: str | os.PathLike) -> Field:
    """A shipped field by name (``"flat"``, ``"rough_flat"``, ``"double_hill"``, ``"arctan"``)
    or a field file of your own (``.json``, format in the module docstring)."""
    s = os.fspath(name_or_path)
    path = s if (s.endswith(".json") or os.sep in s) else os.path.join(FIELDS_FOLDER, s + ".json")
    if not os.path.exists(path):
        raise ValueError(f"no field {s!r}: give a path to a .json field file or one of "
                         f"{', '.join(field_names())}")
    try:
        with open(path, encoding="utf-8") as fh:
            spec = json.load(fh)
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path}: not valid JSON ({exc})") from None
    return Field.from_dict(spec, source=os.path.basename(path))
