"""Minigolf fields: a surface z = H(x, y), a boundary, a hole, a ball region, a surface speed,
the situations played on it and how its teacher picks good shots.

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
      "stimp": 10,                               # surface speed (Stimpmeter, feet), or
      "rolling_resistance": 0.0785,              # rho directly (deceleration (5/7) rho g)
      "situations": {                            # optional: the situations played
        "ball": {"fixed": [0.1, 0.0]},           # {"fixed": [x, y]}, {"region": [...]} or
        "hole": {"slider": [[2.4, -0.42], [2.4, 0.42]]}   # {"slider": [[x0, y0], [x1, y1]]}
      },
      "teacher": {"strategy": "fixed_speed"}     # optional: how good shots are picked
    }

**Situations** (``"situations"``, :mod:`seds_casadi.minigolf.situations`): where the ball may
lie and where the hole may be, each a fixed point, a slider (a segment, e.g. the hole moved
along the far edge as in the paper's Fig. 9 and 12) or a region. The situation the learners
see is s = hole - ball. The teacher's data set, Table 1's test situations and the shots of
``play`` and ``validate`` are all drawn from this one declaration. **Default** (files without
the entry, and a missing ``ball`` or ``hole`` in it): the ball anywhere in ``ball_region``, the
hole at ``hole``. A declared ball placement must lie inside ``ball_region``, a hole placement
one hole radius inside the bounds; the ball and the hole may both move only on a plane.

**Teacher** (``"teacher"``, all entries optional; see :class:`~seds_casadi.minigolf.teacher.
Teacher`): ``strategy``, one of :data:`TEACHER_STRATEGIES` (``"fixed_speed"``: one speed gain
for every situation, the hitting angle chosen; ``"minimal_speed"``: the slowest hits that sink
(over a 1 deg interval of angles), with a 3 % margin; ``"centre"``: the hit farthest inside its
success region; default ``"centre"``), ``kappa`` (the fixed speed gain), ``alpha_range`` [deg]
and ``kappa_range`` (the search box) and ``banks`` (whether shots off a wall count, default
false).

Surface shapes (``"shape"`` and its parameters):

* ``"plane"``: ``slope_x``, ``slope_y`` (dz/dx, dz/dy; 0 and 0 for the flat field);
* ``"hills"``: ``hills``, a list of Gaussian hills ``height * exp(-|p - c|^2 / (2 width^2))``
  (a negative height makes a hollow);
* ``"arctan"``: ``height * arctan(steepness * (y - y0)) / (pi/2)`` over the field, the paper's
  "scaled evaluation of the arctan function over a grid": a cross slope that bends the ball's path
  (``axis`` "y" or "x" chooses the direction it rises along);
* ``"rough"``: ``bumps`` random Gaussian bumps of ``amplitude`` and ``width`` (seeded by ``seed``),
  plus ``friction_variation``, the relative amplitude of a smooth random variation of the rolling
  resistance: small irregularities that scatter shots (the paper's rough flat field);
* ``"heightmap"``: ``extent`` [xmin, xmax, ymin, ymax] and ``heights`` (rows along y, columns
  along x), interpolated by a bicubic spline.

Every entry is checked before the field is built (:mod:`seds_casadi.minigolf.field_schema`):
an unknown or misspelt entry is an error with a "did you mean" (``"description"`` holds free
text), as are entries of the wrong JSON type and sizes beyond the limits listed there (a field
at most 100 m on a side, at most 5000 bumps, a 1 cm table of a rough or height-map surface of
at most a million points).

The surface itself (its shapes' formulas, derivatives and CasADi form) is
:class:`~seds_casadi.minigolf.surface.Surface`.

Rolling resistance by Stimpmeter reading (Penner, "The Physics of Putting", 2002): 6 -> 0.131,
8 -> 0.0985, 10 -> 0.0785, 12 -> 0.0655, interpolated linearly in 1/S in between (rho follows
a 1/S law, see :func:`stimp_to_rho`).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field

import numpy as np

from ..core._io import InputFileError, data_folder, open_regular
from .field_schema import MAX_FILE_BYTES, TEACHER_KEYS, check_field_spec, did_you_mean, plain_numbers
from .situations import Situations
from .surface import Surface

__all__ = ["Field", "load_field", "field_names", "FIELDS_FOLDER", "stimp_to_rho",
           "TEACHER_STRATEGIES"]

#: folder of the shipped field files (the repository's ``fields/``, installed as package data)
FIELDS_FOLDER = data_folder("seds_casadi._fields")
#: the teacher's strategies a field file may name (``"teacher": {"strategy": ...}``)
TEACHER_STRATEGIES = ("fixed_speed", "minimal_speed", "centre")
_STIMP = np.array([[6.0, 0.131], [8.0, 0.0985], [10.0, 0.0785], [12.0, 0.0655]])


def stimp_to_rho(stimp: float) -> float:
    """Rolling-resistance coefficient rho for a Stimpmeter reading S (feet), 6 to 12.

    The ball leaves the Stimpmeter at v0 = 1.83 m/s and rolls S at the deceleration
    (5/7) rho g, so rho = v0^2 / (2 (5/7) g S): a 1/S law. Penner's table is therefore
    interpolated linearly in 1/S (exact at its four readings; within 0.4 % of the law between
    them, where interpolating in S was 2.5 % off at S = 7).
    """
    try:
        s = float(stimp)
    except (TypeError, ValueError):
        raise ValueError(f"stimp must be a number of feet (6 to 12), got {stimp!r}") from None
    if not 6.0 <= s <= 12.0:
        raise ValueError(f"stimp must be between 6 and 12 (feet), got {stimp}")
    inv = 1.0 / _STIMP[::-1, 0]  # increasing
    return float(np.interp(1.0 / s, inv, _STIMP[::-1, 1]))


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
    wall_restitution : float
    situations : Situations
        Where the ball and the hole may be (the file's ``"situations"``, or the default).
    teacher : dict
        The file's ``"teacher"`` settings (validated; empty when the file has none).
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
    situations: Situations | None = None
    teacher: dict = field(default_factory=dict)

    @classmethod
    def from_dict(cls, spec: dict, source: str = "field") -> Field:
        """Validate a field specification and build the field; errors name the entry."""
        check_field_spec(spec, source)
        for key in ("name", "surface", "bounds", "hole", "ball_region"):
            if key not in spec:
                raise ValueError(f"{source}: missing entry {key!r}")
        bounds = _box(spec["bounds"], f"{source}: bounds")
        region = _box(spec["ball_region"], f"{source}: ball_region")
        if not (bounds[0] <= region[0] and region[1] <= bounds[1] and bounds[2] <= region[2]
                and region[3] <= bounds[3]):
            raise ValueError(f"{source}: ball_region {plain_numbers(region)} is not inside the "
                             f"bounds {plain_numbers(bounds)}")
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
            raise ValueError(f"{source}: hole at {plain_numbers(hxy)} is outside the field "
                             f"{plain_numbers(bounds)}")
        if "rolling_resistance" in spec:
            rho = float(spec["rolling_resistance"])
            if not (np.isfinite(rho) and rho >= 0):
                raise ValueError(f"{source}: rolling_resistance must be >= 0, got {rho}")
        elif "stimp" in spec:
            try:
                rho = stimp_to_rho(spec["stimp"])
            except ValueError as exc:
                raise ValueError(f"{source}: {exc}") from None
        else:
            raise ValueError(f"{source}: missing entry 'stimp' or 'rolling_resistance'")
        e = float(spec.get("wall_restitution", 0.6))
        if not 0 <= e <= 1:
            raise ValueError(f"{source}: wall_restitution must be in [0, 1], got {e}")
        try:
            surface = Surface.from_spec(spec["surface"], bounds.tolist(), f"{source}: surface")
            situations = Situations.from_spec(spec.get("situations"), hxy, region, bounds, hr,
                                              surface.shape, source)
        except (TypeError, KeyError, IndexError, AttributeError) as exc:
            raise ValueError(f"{source}: surface or situations: an entry of the wrong type "
                             f"({type(exc).__name__}: {exc}); see the field format") from None
        teacher = _teacher_settings(spec.get("teacher", {}), f"{source}: teacher")
        return cls(str(spec["name"]), surface, bounds, boundary, hxy, hr, region, rho, e, spec,
                   situations, teacher)

    def check_situation(self, ball_xy) -> np.ndarray:
        """Validate ball positions (n, 2) against the ball region; returns them as an array."""
        B = np.atleast_2d(np.asarray(ball_xy, dtype=float))
        if B.shape[1] != 2 or not np.all(np.isfinite(B)):
            raise ValueError(f"ball positions must be finite, shape (n, 2); got {B.shape}")
        r = self.ball_region
        bad = ~((r[0] <= B[:, 0]) & (B[:, 0] <= r[1]) & (r[2] <= B[:, 1]) & (B[:, 1] <= r[3]))
        if bad.any():
            raise ValueError(f"ball position {plain_numbers(B[np.argmax(bad)])} is outside the "
                             f"field's ball region {plain_numbers(r)}")
        return B


def _teacher_settings(t, where: str) -> dict:
    """The ``"teacher"`` entry checked: known keys, a known strategy, a positive speed gain,
    (low, high) ranges and a boolean ``banks``."""
    if not isinstance(t, dict):
        raise ValueError(f"{where}: an object is needed, got {t!r}")
    unknown = sorted(set(t) - set(TEACHER_KEYS))
    if unknown:
        raise ValueError(f"{where}: unknown entry {unknown[0]!r}; valid: {', '.join(TEACHER_KEYS)}")
    out = dict(t)
    if "strategy" in t and t["strategy"] not in TEACHER_STRATEGIES:
        raise ValueError(f"{where}.strategy: unknown strategy {t['strategy']!r}; valid: "
                         f"{', '.join(TEACHER_STRATEGIES)}")
    if "kappa" in t:
        k = t["kappa"]
        if isinstance(k, bool) or not isinstance(k, (int, float)) or not (np.isfinite(k) and k > 0):
            raise ValueError(f"{where}.kappa: a positive speed gain is needed, got {k!r}")
    for key in ("alpha_range", "kappa_range"):
        if key in t:
            try:
                lo, hi = (float(v) for v in t[key])
            except (TypeError, ValueError):
                raise ValueError(f"{where}.{key}: [low, high] of numbers needed, got "
                                 f"{t[key]!r}") from None
            if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi) or (
                    key == "kappa_range" and lo <= 0):
                raise ValueError(f"{where}.{key}: [low, high] with low < high"
                                 f"{' and low > 0' if key == 'kappa_range' else ''} needed, got "
                                 f"{t[key]!r}")
            out[key] = (lo, hi)
    if "banks" in t and not isinstance(t["banks"], bool):
        raise ValueError(f"{where}.banks: true or false, got {t['banks']!r}")
    return out


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
    or a field file of your own (``.json``, format in the module docstring).

    A field file must be a regular file of at most
    :data:`~seds_casadi.minigolf.field_schema.MAX_FILE_BYTES` bytes (a named pipe or a device
    is refused before it is opened), and its ``name`` a plain name (it names the files the
    commands write); anything wrong is a ``ValueError`` naming the file and the entry."""
    s = os.fspath(name_or_path)
    path = s if (s.endswith(".json") or os.sep in s) else os.path.join(FIELDS_FOLDER, s + ".json")
    if not os.path.exists(path):
        hint = did_you_mean(s, field_names()) if path.startswith(FIELDS_FOLDER) else ""
        raise ValueError(f"no field {s!r}{hint}: give a path to a .json field file or one of "
                         f"{', '.join(field_names())}")
    if os.path.isdir(path):
        raise ValueError(f"{path} is a folder; give a .json field file or a field name")
    try:
        with open_regular(path, MAX_FILE_BYTES, "field file", text=True,
                          encoding="utf-8-sig") as fh:
            spec = json.load(fh)
    except InputFileError:  # not a regular file, too large: the message names it
        raise
    except ValueError as exc:  # JSONDecodeError, UnicodeDecodeError, an integer of more
        # digits than Python converts (sys.get_int_max_str_digits)
        raise ValueError(f"{path}: not valid JSON ({exc})") from None
    except RecursionError:
        raise ValueError(f"{path}: nested too deeply to be a field file") from None
    except OSError as exc:
        raise ValueError(f"{path}: cannot be read ({exc.strerror})") from None
    return Field.from_dict(spec, source=os.path.basename(path))
