"""A cache of the teacher's data sets, so that a second ``seds-casadi play`` on the same field
and motion skips the teacher (its longest stage).

A data set is stored under ``<cache>/teacher/<key>.npz`` (``<cache>``: ``$SEDS_CASADI_CACHE``
or ``~/.cache/seds_casadi``, shared with the compiled kernels), where the key hashes everything
the teacher's result depends on: the field's specification, the stroke (the motion's psi*, v*,
club mass and restitution), the teacher's settings and the source of the modules that compute
it (teacher, ball model, surfaces, fields, situations), so a change of any of them is a miss.
A damaged or unreadable entry is computed again and replaced.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os

from ..codegen.cache import cache_folder

__all__ = ["cached_dataset", "dataset_key"]

_LOG = logging.getLogger(__name__)

#: the modules whose code decides the teacher's data set
_SOURCES = ("teacher", "hitting_data", "ball", "ball_kernel", "ball_physics", "stroke", "surface",
            "fields", "field_schema", "situations")


def dataset_key(field, stroke, settings: dict) -> str:
    """The cache key (hex) of the teacher's data set for ``field``, ``stroke`` and the
    teacher's ``settings`` (keyword arguments of
    :func:`~seds_casadi.minigolf.teacher.collect_dataset`)."""
    from .. import minigolf

    h = hashlib.sha256()
    h.update(json.dumps({"field": field.spec, "stroke": stroke.to_dict(),
                         "settings": settings}, sort_keys=True, default=str).encode())
    folder = os.path.dirname(minigolf.__file__)
    for name in _SOURCES:
        with open(os.path.join(folder, f"{name}.py"), "rb") as fh:
            h.update(fh.read())
    return h.hexdigest()[:32]


def cached_dataset(field, stroke, use_cache: bool = True, progress: bool = False,
                   **settings):
    """The teacher's data set (:func:`~seds_casadi.minigolf.teacher.collect_dataset`), from the
    cache when an entry for the same field, stroke, settings and code exists.

    Returns
    -------
    (HittingDataset, bool)
        The data set and whether it came from the cache.
    """
    from ..minigolf.hitting_data import HittingDataset
    from ..minigolf.teacher import collect_dataset

    path = os.path.join(cache_folder(), "teacher", dataset_key(field, stroke, settings) + ".npz")
    if use_cache and os.path.exists(path):
        try:
            return HittingDataset.load(path), True
        except (ValueError, OSError, KeyError) as exc:
            _LOG.warning("the cached teacher's data set %s is unreadable (%s): computing it "
                         "again", path, exc)
    data = collect_dataset(field, stroke, progress=progress, **settings)
    if use_cache:
        try:
            os.makedirs(os.path.dirname(path), exist_ok=True)
            data.save(path)
        except OSError as exc:  # a read-only cache is no reason to fail the run
            _LOG.warning("could not cache the teacher's data set in %s (%s)", path, exc)
    return data, False
