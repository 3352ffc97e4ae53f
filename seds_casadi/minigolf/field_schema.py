"""The schema of a field file, checked before a field is built: the entries each level may
hold (an unknown or misspelt one is an error with a "did you mean"), their JSON types, and the
size limits that keep a field from allocating more than a computer has. A field's ``name`` is a
plain name (:data:`~seds_casadi.core._io.PLAIN_NAME`: letters, digits, ``.``, ``_``, ``-``, at
most 64, not starting with ``.`` or ``-``): the commands name files after it.

The limits: a field at most :data:`MAX_EXTENT` metres on a side; at most :data:`MAX_HILLS` hills
and :data:`MAX_BUMPS` random bumps; a height map of at most :data:`MAX_HEIGHTMAP_VALUES`
heights; a tabulated surface (``"rough"``, ``"heightmap"``: the compiled ball engine reads a
1 cm table of it) of at most :data:`MAX_TABLE_POINTS` grid points, and at most
:data:`MAX_BUMP_EVALUATIONS` bump evaluations to fill that table; a field file of at most
:data:`MAX_FILE_BYTES` bytes.
"""

from __future__ import annotations

import difflib
import math

from ..core._io import is_plain_name

__all__ = ["check_field_spec", "did_you_mean", "plain_numbers", "FIELD_KEYS", "SURFACE_KEYS",
           "TEACHER_KEYS",
           "MAX_EXTENT", "MAX_HILLS", "MAX_BUMPS", "MAX_HEIGHTMAP_VALUES", "MAX_TABLE_POINTS",
           "MAX_BUMP_EVALUATIONS", "MAX_FILE_BYTES"]

#: the entries of a field file (``description``: free text, ignored)
FIELD_KEYS = ("name", "description", "surface", "bounds", "boundary", "wall_restitution", "hole",
              "ball_region", "stimp", "rolling_resistance", "situations", "teacher")
#: the entries of ``"surface"`` by shape
SURFACE_KEYS = {"plane": ("slope_x", "slope_y"), "hills": ("hills",),
                "arctan": ("height", "steepness", "y0", "axis"),
                "rough": ("amplitude", "width", "bumps", "friction_variation", "seed"),
                "heightmap": ("extent", "heights")}
#: the entries of a field file's ``"teacher"``
TEACHER_KEYS = ("strategy", "kappa", "alpha_range", "kappa_range", "banks")
_HOLE_KEYS = ("x", "y", "radius")
_HILL_KEYS = ("x", "y", "height", "width")
#: a field's largest side [m]
MAX_EXTENT = 100.0
MAX_HILLS = 1000
MAX_BUMPS = 5000
MAX_HEIGHTMAP_VALUES = 1_000_000
#: grid points of the 1 cm table of a tabulated surface (e.g. 10 m x 10 m)
MAX_TABLE_POINTS = 1_000_000
#: grid points times bumps when a rough surface is tabulated (memory of about 1 GB)
MAX_BUMP_EVALUATIONS = 20_000_000
MAX_FILE_BYTES = 64 * 1024 * 1024
_SPACING = 0.01  # the table's spacing, as Surface.table


def did_you_mean(name: str, valid) -> str:
    """`` (did you mean 'x'?)`` for the closest valid name, or an empty string."""
    close = difflib.get_close_matches(str(name), list(valid), n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


def plain_numbers(values) -> str:
    """``values`` (a list, tuple or array of numbers) as a user reads them in a message:
    ``[3.2, -0.5]`` (not ``[np.float64(3.2), ...]``), each number in ``%g`` form."""
    return "[" + ", ".join(f"{float(v):g}" for v in values) + "]"


def _known(d: dict, valid, where: str) -> None:
    for key in d:
        if key not in valid:
            raise ValueError(f"{where}: unknown entry {key!r}{did_you_mean(key, valid)}; valid: "
                             f"{', '.join(valid)}")


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _numbers(spec: dict, keys, where: str) -> None:
    for k in keys:
        if k in spec and not _is_number(spec[k]):
            raise ValueError(f"{where}.{k}: a number is needed, got {spec[k]!r}")


def check_field_spec(spec: dict, source: str) -> None:
    """Check a field specification's entries, types and sizes (module docstring); raises a
    ``ValueError`` naming the file and the entry."""
    if not isinstance(spec, dict):
        raise ValueError(f"{source}: a field is a JSON object, got {type(spec).__name__}")
    _known(spec, FIELD_KEYS, source)
    _numbers(spec, ("wall_restitution", "stimp", "rolling_resistance"), source)
    if "stimp" in spec and "rolling_resistance" in spec:
        raise ValueError(f"{source}: both 'stimp' ({spec['stimp']!r}) and 'rolling_resistance' "
                         f"({spec['rolling_resistance']!r}) given; they set the same surface speed, "
                         "keep one")
    if "name" in spec and not isinstance(spec["name"], str):
        raise ValueError(f"{source}: name: a text is needed, got {spec['name']!r}")
    if "name" in spec and not is_plain_name(spec["name"]):
        raise ValueError(
            f"{source}: name {spec['name']!r} is not a plain name: the commands name files "
            "after it (datasets/NAME.npz, models/dataset_NAME.npz), so it may hold only "
            "letters, digits, '.', '_' and '-', at most 64, not starting with '.' or '-' "
            "(e.g. 'my_green_2')")
    hole = spec.get("hole")
    if hole is not None:
        if not isinstance(hole, dict):
            raise ValueError(f"{source}: hole: an object {{\"x\": .., \"y\": .., \"radius\": ..}} "
                             f"is needed, got {hole!r}")
        _known(hole, _HOLE_KEYS, f"{source}: hole")
        _numbers(hole, _HOLE_KEYS, f"{source}: hole")
    for key in ("situations", "teacher"):
        if key in spec and not isinstance(spec[key], dict):
            raise ValueError(f"{source}: {key}: an object is needed, got {spec[key]!r}")
    if "teacher" in spec:
        _known(spec["teacher"], TEACHER_KEYS, f"{source}: teacher")
    extent = _extent(spec.get("bounds"), source)
    surface = spec.get("surface")
    if surface is not None:
        _check_surface(surface, extent, f"{source}: surface")


def _extent(bounds, source: str) -> tuple[float, float] | None:
    if not (isinstance(bounds, list) and len(bounds) == 4 and all(map(_is_number, bounds))):
        return None  # Field.from_dict reports the bounds' own errors
    w, h = bounds[1] - bounds[0], bounds[3] - bounds[2]
    if max(w, h) > MAX_EXTENT:
        raise ValueError(f"{source}: bounds: a field of {w:g} m x {h:g} m; at most "
                         f"{MAX_EXTENT:g} m on a side is supported")
    return (w, h) if math.isfinite(w) and math.isfinite(h) else None


def _check_surface(surface, extent, where: str) -> None:
    if not isinstance(surface, dict):
        raise ValueError(f"{where}: an object with an entry 'shape' is needed, got {surface!r}")
    shape = surface.get("shape")
    if not isinstance(shape, str) or shape not in SURFACE_KEYS:
        raise ValueError(f"{where}.shape: unknown shape {shape!r}{did_you_mean(shape, SURFACE_KEYS)}"
                         f"; valid: {', '.join(SURFACE_KEYS)}")
    valid = ("shape", *SURFACE_KEYS[shape])
    _known(surface, valid, where)
    _numbers(surface, [k for k in SURFACE_KEYS[shape] if k not in ("hills", "extent", "heights",
                                                                    "axis")], where)
    points = None if extent is None else (
        (math.ceil(extent[0] / _SPACING) + 1) * (math.ceil(extent[1] / _SPACING) + 1))
    if shape in ("rough", "heightmap") and points is not None and points > MAX_TABLE_POINTS:
        raise ValueError(f"{where}: a {shape!r} surface over {extent[0]:g} m x {extent[1]:g} m "
                         f"needs a table of {points} points at 1 cm; at most {MAX_TABLE_POINTS} "
                         "are supported (make the field smaller)")
    if shape == "hills":
        _check_hills(surface.get("hills"), where)
    elif shape == "rough":
        _check_bumps(surface, points, where)
    elif shape == "heightmap":
        _check_heightmap(surface.get("heights"), where)


def _check_hills(hills, where: str) -> None:
    if not isinstance(hills, list):
        return  # Surface.from_spec: "a non-empty list of hills is needed"
    if len(hills) > MAX_HILLS:
        raise ValueError(f"{where}.hills: {len(hills)} hills; at most {MAX_HILLS} are supported")
    for i, h in enumerate(hills):
        if not isinstance(h, dict):
            raise ValueError(f"{where}.hills[{i}]: an object with x, y, height, width is "
                             f"needed, got {h!r}")
        _known(h, _HILL_KEYS, f"{where}.hills[{i}]")
        _numbers(h, _HILL_KEYS, f"{where}.hills[{i}]")


def _check_bumps(surface: dict, points, where: str) -> None:
    n = surface.get("bumps")
    if n is None:
        return
    if not (_is_number(n) and math.isfinite(n) and n == int(n) and n >= 1):
        raise ValueError(f"{where}.bumps: a whole number of bumps >= 1 is needed, got {n!r}")
    if n > MAX_BUMPS:
        raise ValueError(f"{where}.bumps: {int(n)} bumps; at most {MAX_BUMPS} are supported")
    if points is not None and points * n > MAX_BUMP_EVALUATIONS:
        raise ValueError(f"{where}: {int(n)} bumps over {points} table points is more than the "
                         f"{MAX_BUMP_EVALUATIONS} evaluations supported; use fewer bumps or a "
                         "smaller field")
    seed = surface.get("seed", 0)
    if not (_is_number(seed) and seed == int(seed) and 0 <= seed < 2**63):
        raise ValueError(f"{where}.seed: a whole number >= 0 is needed, got {seed!r}")


def _check_heightmap(heights, where: str) -> None:
    if not isinstance(heights, list):
        raise ValueError(f"{where}.heights: a list of rows of heights is needed, got "
                         f"{type(heights).__name__}")
    if not heights or not all(isinstance(r, list) for r in heights):
        return  # Surface.from_spec: "a 2-D grid of at least 4 x 4 heights"
    rows, cols = len(heights), len(heights[0])
    if rows * cols > MAX_HEIGHTMAP_VALUES:
        raise ValueError(f"{where}.heights: {rows} x {cols} heights; at most "
                         f"{MAX_HEIGHTMAP_VALUES} values are supported")
    for i, r in enumerate(heights):
        if not (isinstance(r, list) and len(r) == cols and all(map(_is_number, r))):
            raise ValueError(f"{where}.heights[{i}]: every row must be a list of {cols} "
                             "numbers")
