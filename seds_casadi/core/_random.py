"""Seeds: the ``random_state`` conventions of the package in the form scikit-learn accepts."""

from __future__ import annotations

import numpy as np


def sklearn_random_state(random_state):
    """An int, None, ``RandomState`` or numpy ``Generator`` as a seed scikit-learn accepts.

    A ``Generator`` gives an int drawn from it (so a Generator passed twice gives two different,
    reproducible seeds); anything else is passed on unchanged for scikit-learn to check.
    """
    if isinstance(random_state, np.random.Generator):
        return int(random_state.integers(2**31 - 1))
    return random_state
