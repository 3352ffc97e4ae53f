"""The guarded file of a :class:`~seds_casadi.minigolf.strategies.StrategySet`
(``strategies_<field>.npz``): format, version, checksum (:mod:`seds_casadi.core.model_files`)
and re-validation on load; angles in degrees. ``StrategySet.save`` and ``StrategySet.load`` call
:func:`write_strategies` and :func:`read_strategies`; this module knows the file, not the class.
"""

from __future__ import annotations

import os

import numpy as np

from ..core.errors import ModelFileError
from ..core.model_files import read_guarded, write_guarded
from .hitting_data import HittingDataset

STRATEGIES_FORMAT = "seds_casadi.StrategySet"
STRATEGIES_VERSION = 2  # 1: without a checksum (refused)


def write_strategies(path: str | os.PathLike, ss) -> None:
    """Write a strategy set (a :class:`~seds_casadi.minigolf.strategies.StrategySet`; atomic;
    no pickle)."""
    arrays = {"ball": ss.ball, "hole": ss.hole, "robustness": ss.robustness}
    for s in ss.strategies:
        d = s.data
        arrays[f"s{s.label}_ball"], arrays[f"s{s.label}_hole"] = d.ball, d.hole
        arrays[f"s{s.label}_alpha_deg"], arrays[f"s{s.label}_kappa"] = d.alpha_deg, d.kappa
    meta = {"field": ss.field, "stroke": ss.stroke.to_dict(), "settings": ss.settings,
            "walls": [int(s.walls) for s in ss.strategies],
            "routes": [list(s.routes) for s in ss.strategies]}
    write_guarded(path, STRATEGIES_FORMAT, STRATEGIES_VERSION, arrays, meta)


def _schema(meta: dict) -> dict:
    out = {"ball": 2, "hole": 2, "robustness": 2}
    for k in range(len(meta["walls"])):
        out.update({f"s{k}_ball": 2, f"s{k}_hole": 2, f"s{k}_alpha_deg": 1, f"s{k}_kappa": 1})
    return out


def read_strategies(path: str | os.PathLike) -> tuple[dict, dict, list[HittingDataset]]:
    """Read and re-validate a file written by :func:`write_strategies`; anything wrong raises
    :class:`~seds_casadi.ModelFileError` naming the file.

    Returns
    -------
    meta : dict
        ``field``, ``stroke``, ``settings``, and per strategy its ``walls`` and ``routes``.
    arrays : dict
        ``ball``, ``hole`` of the explored situations, shape (n, 2), and ``robustness``, shape
        (n, n_strategies).
    data : list of HittingDataset
        Each strategy's shots (labelled with its index).
    """
    path = os.fspath(path)
    a, meta, _ = read_guarded(path, STRATEGIES_FORMAT, (STRATEGIES_VERSION,), _schema)
    n, m = len(a["ball"]), len(meta["walls"])
    R = a["robustness"]
    if a["ball"].shape != (n, 2) or a["hole"].shape != (n, 2) or R.shape != (n, m):
        raise ModelFileError(f"{path}: the situations and robustness have inconsistent shapes")
    if np.any((R < 0) | (R > 1)):
        raise ModelFileError(f"{path}: entry 'robustness' holds values outside [0, 1]")
    routes, walls = meta.get("routes"), meta["walls"]
    if not (isinstance(routes, list) and len(routes) == m and isinstance(meta.get("settings"),
                                                                          dict)):
        raise ModelFileError(f"{path}: entry 'meta' has no routes per strategy or no settings")
    if m == 0:
        raise ModelFileError(f"{path}: the file holds no strategy")
    data = []
    for k, w in enumerate(walls):
        arrays = {"ball": a[f"s{k}_ball"], "hole": a[f"s{k}_hole"],
                  "alpha_deg": a[f"s{k}_alpha_deg"], "kappa": a[f"s{k}_kappa"],
                  "labels": np.full(len(a[f"s{k}_kappa"]), k)}
        ds = HittingDataset.from_arrays(arrays, {"field": meta["field"], "strategy": "centre",
                                                 "dropped": 0, "stroke": meta["stroke"]}, path)
        if not (isinstance(w, int) and isinstance(routes[k], list)
                and len(routes[k]) == len(ds)):
            raise ModelFileError(f"{path}: strategy {k}: walls or routes do not fit its shots")
        data.append(ds)
    return meta, {"ball": a["ball"], "hole": a["hole"], "robustness": R}, data
