"""The surface of a field, z = H(x, y): its shapes, their validation, and H with its gradient,
Hessian and friction factor, vectorised in numpy and symbolic in CasADi.

Shapes and their parameters are listed in :mod:`seds_casadi.minigolf.fields` (the field file
format). The analytic shapes ("plane", "hills", "arctan") have CasADi forms of the same
formulas; the tabulated ones ("rough", "heightmap") are read by the compiled ball engine from a
table of derivatives on a grid (:meth:`Surface.table`).
"""

from __future__ import annotations

import json

import casadi as ca
import numpy as np

from .field_schema import plain_numbers

#: the surface shapes a field file may use
SHAPES = ("plane", "hills", "arctan", "rough", "heightmap")
#: steepest slope |grad H| a field's surface may have (84 deg: steeper is a wall, not a green;
#: the shipped fields reach 0.17, a sinkhole 1 m deep and 15 cm wide 4)
MAX_SLOPE = 10.0
#: extremes of the surfaces seen (shape, parameters, bounds) -> dict, see Surface.extremes
_EXTREMES: dict = {}


# ---------------------------------------------------------------- validation of a specification
def _number(p: dict, where: str, key: str, positive: bool = False, default=None) -> float:
    """The entry ``key`` of the specification ``p`` as a finite (or positive) number; a missing
    entry takes ``default`` (written into ``p``) or is an error."""
    if key not in p:
        if default is None:
            raise ValueError(f"{where}: missing entry {key!r} for shape {p['shape']!r}")
        p[key] = default
    try:
        v = float(p[key])
    except (TypeError, ValueError):
        raise ValueError(f"{where}.{key}: not a number: {p[key]!r}") from None
    if not np.isfinite(v) or (positive and v <= 0):
        raise ValueError(f"{where}.{key}: must be {'positive' if positive else 'finite'},"
                         f" got {p[key]!r}")
    return v


def _check_plane(p: dict, bounds, where: str) -> None:
    _number(p, where, "slope_x", default=0.0)
    _number(p, where, "slope_y", default=0.0)


def _check_hills(p: dict, bounds, where: str) -> None:
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


def _check_arctan(p: dict, bounds, where: str) -> None:
    _number(p, where, "height")
    _number(p, where, "steepness", positive=True)
    _number(p, where, "y0", default=0.0)
    if p.get("axis", "y") not in ("x", "y"):
        raise ValueError(f"{where}.axis: 'x' or 'y', got {p.get('axis')!r}")


def _check_rough(p: dict, bounds, where: str) -> None:
    _number(p, where, "amplitude")
    _number(p, where, "width", positive=True)
    _number(p, where, "bumps", positive=True)
    _number(p, where, "friction_variation", default=0.0)
    if not 0 <= float(p["friction_variation"]) < 1:
        raise ValueError(f"{where}.friction_variation: must be in [0, 1)")
    p["_bounds"] = bounds


def _check_heightmap(p: dict, bounds, where: str) -> None:
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
        raise ValueError(f"{where}.extent {plain_numbers(ext)} does not cover the field's bounds "
                         f"{plain_numbers(bounds)}")


_CHECKS = {"plane": _check_plane, "hills": _check_hills, "arctan": _check_arctan,
           "rough": _check_rough, "heightmap": _check_heightmap}


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
        """Validate a surface specification (see :mod:`seds_casadi.minigolf.fields`) and build
        it; errors name the entry (``where``)."""
        if not isinstance(spec, dict) or "shape" not in spec:
            raise ValueError(f"{where}: needs an entry 'shape' (one of {', '.join(SHAPES)})")
        shape = spec["shape"]
        if shape not in SHAPES:
            raise ValueError(f"{where}.shape: unknown shape {shape!r}; valid: {', '.join(SHAPES)}")
        p = dict(spec)
        _CHECKS[shape](p, bounds, where)
        surface = cls(shape, p)
        surface._check_followable(bounds, where)
        return surface

    def _check_followable(self, bounds, where: str) -> None:
        """Refuse a surface steeper than :data:`MAX_SLOPE` or curved more tightly than the ball's
        radius: the ball (a sphere touching at one point) cannot follow it, and the step would
        not stay finite. Both from :meth:`extremes`, which adds the points where an arctan's or
        a bump's extremes lie in closed form to its grid."""
        from ..motion.golf import BALL_RADIUS

        ext = self.extremes(bounds)
        if ext["curvature"] * BALL_RADIUS > 1.0:
            x, y = ext["where"]
            raise ValueError(
                f"{where}: the surface curves with a radius of {1e3 / ext['curvature']:.3g} mm"
                f" near ({x:.3f}, {y:.3f}), tighter than the ball's radius "
                f"({1e3 * BALL_RADIUS:.2f} mm): a ball cannot follow it. Smooth the surface "
                "(smaller height differences between neighbouring points, wider bumps).")
        if ext["slope"] > MAX_SLOPE:
            raise ValueError(
                f"{where}: the surface rises {ext['slope']:.3g} m per metre at its steepest, "
                f"more than {MAX_SLOPE:g} (84 deg): a slope that steep is a wall, not a green the "
                "ball model rolls on. Use gentler slopes (the shipped fields reach 0.17).")

    def _terms(self, Q):
        """Height, gradient and Hessian entries (xx, xy, yy) at Q (n, 2); the sums of bumps in
        one pass (for :meth:`extremes`)."""
        if self.shape not in ("hills", "rough"):
            H = self.hessian(Q)
            return self.height(Q), self.gradient(Q), (H[:, 0, 0], H[:, 0, 1], H[:, 1, 1])
        dx = Q[:, 0, None] - self._c[None, :, 0]
        dy = Q[:, 1, None] - self._c[None, :, 1]
        w2 = self._w**2
        g = self._a * np.exp(-(dx * dx + dy * dy) / (2 * w2))
        gw = g / w2
        grad = -np.column_stack([np.sum(gw * dx, axis=1), np.sum(gw * dy, axis=1)])
        hxx = np.sum(gw * (dx * dx / w2 - 1), axis=1)
        hyy = np.sum(gw * (dy * dy / w2 - 1), axis=1)
        return g.sum(axis=1), grad, (hxx, np.sum(gw * dx * dy / w2, axis=1), hyy)

    def extremes(self, bounds, spacing: float = 0.01) -> dict:
        """Largest |H| range, slope and curvature over ``bounds`` (sampled on a grid, at most
        ``spacing`` apart, finer for narrow hills and fine height maps, plus the points where an
        arctan's or a bump's extremes lie in closed form).

        Returns a dict: ``height_range`` [m], ``slope`` (largest |grad H|), ``curvature``
        (largest spectral norm of Hess(H), 1/m; at least the surface's largest principal
        curvature) and ``where`` (the point of largest curvature). Cached per bounds.
        """
        key = (self.shape, json.dumps(self.params, sort_keys=True, default=str),
               tuple(float(v) for v in bounds), float(spacing))
        if key in _EXTREMES:
            return _EXTREMES[key]
        b = np.asarray(key[2])
        # finer for narrow hills (4 samples a width) and fine height maps (2 a cell), at most
        # 4 million points (the hills' centres are checked exactly below)
        finest = np.sqrt(max((b[1] - b[0]) * (b[3] - b[2]), 1e-12) / 4e6)
        if self.shape == "hills":
            spacing = min(spacing, max(float(np.min(self._w)) / 4, finest))
        if self.shape == "heightmap":
            ext, Z = self.params["extent"], np.shape(self.params["heights"])
            cell = min((ext[1] - ext[0]) / (Z[1] - 1), (ext[3] - ext[2]) / (Z[0] - 1))
            spacing = min(spacing, max(cell / 2, finest))
        xs = np.linspace(b[0], b[1], max(4, int(np.ceil((b[1] - b[0]) / spacing)) + 1))
        ys = np.linspace(b[2], b[3], max(4, int(np.ceil((b[3] - b[2]) / spacing)) + 1))
        X, Y = np.meshgrid(xs, ys, indexing="ij")
        P = np.column_stack([X.ravel(), Y.ravel()])
        lo, hi, slope, curv, at = np.inf, -np.inf, 0.0, 0.0, P[0]
        chunk = max(256, 400_000 // max(1, len(getattr(self, "_a", [0]))))
        for c in range(0, len(P), chunk):
            Q = P[c:c + chunk]
            h, g, (hxx, hxy, hyy) = self._terms(Q)
            lo, hi = min(lo, h.min()), max(hi, h.max())
            slope = max(slope, float(np.sqrt(np.max(np.sum(g * g, axis=1)))))
            k = np.abs(0.5 * (hxx + hyy)) + np.sqrt((0.5 * (hxx - hyy)) ** 2 + hxy**2)
            i = int(np.argmax(k))
            if k[i] > curv:
                curv, at = float(k[i]), Q[i]
        # and where the extremes are known in closed form (a grid misses a step or a bump
        # narrower than its spacing): the arctan's steepest and most curved lines, the bumps'
        # centres (each bump's largest curvature, |height| / width^2)
        Q = self._critical_points(b)
        if len(Q):
            h, g, (hxx, hxy, hyy) = self._terms(Q)
            lo, hi = min(lo, h.min()), max(hi, h.max())
            slope = max(slope, float(np.sqrt(np.max(np.sum(g * g, axis=1)))))
            k = np.abs(0.5 * (hxx + hyy)) + np.sqrt((0.5 * (hxx - hyy)) ** 2 + hxy**2)
            i = int(np.argmax(k))
            if k[i] > curv:
                curv, at = float(k[i]), Q[i]
        out = dict(height_range=float(hi - lo), slope=slope, curvature=curv,
                   where=(float(at[0]), float(at[1])))
        _EXTREMES[key] = out
        return out

    def _critical_points(self, b: np.ndarray) -> np.ndarray:
        """Points of ``bounds`` ``b`` where the largest slope or curvature lies in closed form:
        an arctan's centre line (steepest) and the lines u = y0 +- 1 / (sqrt(3) steepness)
        (most curved: |H''| peaks there), clipped to the bounds; the bumps' centres inside them."""
        if self.shape == "arctan":
            p = self.params
            axis = 1 if p.get("axis", "y") == "y" else 0
            lo, hi = (b[2], b[3]) if axis == 1 else (b[0], b[1])
            off = 1.0 / (np.sqrt(3.0) * float(p["steepness"]))
            u = np.clip(float(p["y0"]) + np.array([0.0, -off, off]), lo, hi)
            Q = np.zeros((3, 2))
            Q[:, axis] = u
            Q[:, 1 - axis] = b[0] if axis == 1 else b[2]
            return Q
        if self.shape in ("hills", "rough"):
            c = self._c
            inside = (c[:, 0] >= b[0]) & (c[:, 0] <= b[1]) & (c[:, 1] >= b[2]) & (c[:, 1] <= b[3])
            return c[inside]
        return np.zeros((0, 2))

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
