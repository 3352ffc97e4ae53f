"""Playing with several strategies: one hitting-parameter model per strategy, and the strategy
most likely to succeed chosen at each situation (the paper's Section 8 extension; the
strategies come from :mod:`seds_casadi.minigolf.strategies`).

**How the choice is judged.** For every explored situation the exploration knows each
strategy's robustness: the probability that its shot sinks when it is executed with Gaussian
errors of (1 deg, 0.03 in kappa), 0 where the strategy has no success region. A Gaussian process
per strategy learns that robustness over s (the same GPR as the hitting parameters, Eq. 17);
at play time the strategy with the highest predicted robustness is played, with its own model's
(alpha, kappa). The robustness is measured around the teacher's shot, not the learner's: where a
strategy's hitting-parameter model is uncertain the choice does not see it. A situation no
strategy was seen at gets the strategy that is predicted best anyway.
"""

from __future__ import annotations

import numpy as np
from sklearn.base import BaseEstimator

from .parameters import make_model
from .strategies import StrategySet

__all__ = ["StrategyChoice"]


class StrategyChoice(BaseEstimator):
    """Hitting parameters from the strategy most likely to succeed (module docstring).

    A scikit-learn estimator (``get_params``/``set_params``, ``clone``): ``__init__`` stores
    the parameters, :meth:`fit` on a :class:`~seds_casadi.minigolf.strategies.StrategySet`
    (from :func:`~seds_casadi.minigolf.strategies.explore`) returns it with the fitted
    attributes below.

    Parameters
    ----------
    learner : {"gpr", "gmr", "sep_gmr"}
        The hitting-parameter model of each strategy.
    n_components : int
        Gaussians of the GMMs (GMR learners).
    random_state : int

    Attributes
    ----------
    models_ : list
        One fitted hitting-parameter model per strategy (s -> alpha [deg], kappa).
    chance_ : list of GPRModel
        One model of each strategy's robustness over s.
    labels_ : array of int
    """

    def __init__(self, learner: str = "gpr", n_components: int = 3, random_state=0) -> None:
        self.learner = learner
        self.n_components = n_components
        self.random_state = random_state

    def fit(self, strategies: StrategySet) -> StrategyChoice:
        """Fit each strategy's hitting-parameter model on its shots and its robustness model
        on all the explored situations; returns self."""
        if not isinstance(strategies, StrategySet) or len(strategies) == 0:
            raise ValueError("fit needs a StrategySet with at least one strategy")
        kw = {"random_state": self.random_state}
        if self.learner != "gpr":
            kw["n_components"] = self.n_components
        S = strategies.situations
        self.models_, self.chance_ = [], []
        for s in strategies.strategies:
            if len(s.data) < 3:
                raise ValueError(f"{s.describe()} has {len(s.data)} shots, too few to learn; "
                                 f"keep fewer strategies")
            self.models_.append(make_model(self.learner, **kw).fit(s.data.situations,
                                                                   s.data.outputs))
            self.chance_.append(make_model("gpr", random_state=self.random_state).fit(
                S, s.robustness[:, None]))
        self.labels_ = np.array([s.label for s in strategies.strategies])
        return self

    def chances(self, S) -> np.ndarray:
        """Predicted robustness of each strategy at situations S (n, 2), shape (n, k), in
        [0, 1]."""
        return np.clip(np.column_stack([m.predict(S)[:, 0] for m in self.chance_]), 0.0, 1.0)

    def predict_strategy(self, S, k: int) -> np.ndarray:
        """(alpha [deg], kappa) of strategy ``k`` at situations S (n, 2), shape (n, 2)."""
        return self.models_[int(k)].predict(S)

    def predict(self, S, return_choice: bool = False):
        """(alpha [deg], kappa) of the chosen strategy at situations S (n, 2), shape (n, 2);
        with ``return_choice`` also the chosen labels (n,) and the chances (n, k)."""
        S = np.atleast_2d(np.asarray(S, float))
        P = self.chances(S)
        choice = np.argmax(P, axis=1)
        every = np.stack([m.predict(S) for m in self.models_], axis=1)
        out = every[np.arange(len(S)), choice]
        return (out, self.labels_[choice], P) if return_choice else out
