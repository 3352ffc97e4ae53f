"""Learning a hitting motion from demonstrations (scikit-learn estimator): the target field by
SEDS with the direction objective (Eq. 8-11), the strength factor by GMR (Eq. 12), checked from
probe starts and refitted from the next initialisation when swings arrive off psi*.

Choices where the paper leaves them open (documented for users):

* **Approach paths (on by default).** Virtual paths into the ball are added to the SEDS data
  (not to the strength factor) so that swings line up with psi* before they reach it
  (:mod:`seds_casadi.motion.approach`). ``approach_paths=False`` gives the paper's plain problem
  (Eq. 9-11).
* **The probe check.** The fit is checked from probe starts (the demonstrations' first points and
  random points in their box): if a swing misses or arrives more than ``max_direction_error``
  off, SEDS is refitted from the next random initialisation (``restarts``), and the best model
  is kept (a warning says so if none passes).
* **Arrival constraint (an experimental extension, off by default).** ``approach_ratio=4`` adds
  the constraint that the demonstrated arrival direction is an eigenvector of J whose rate is at
  least 4 times slower than any sideways motion (a condition on J at x* only; the approach paths
  work on the flow around it).
"""

from __future__ import annotations

import warnings

import numpy as np
from sklearn.base import BaseEstimator

from ..core.demonstrations import Demonstrations
from ..core.errors import ConvergenceWarning, SEDSError, SolverError
from ..core.seds import SEDS
from .approach import approach_paths, arrival_direction, arrival_speed
from .hitting import HittingMotion
from .strength import StrengthFactor, StrengthFactorLearner
from .target_field import TargetField

__all__ = ["HittingMotionLearner", "probe_starts"]


def probe_starts(demos: Demonstrations, n_random: int = 24) -> np.ndarray:
    """The demonstrations' first points and ``n_random`` fixed random points in their box."""
    first = np.array([p[0] for p in demos.positions])
    lo, hi = first.min(axis=0), first.max(axis=0)
    rng = np.random.default_rng(12345)
    return np.vstack([first, lo + (hi - lo) * rng.random((n_random, 3))])


def _check_demos(demos) -> Demonstrations:
    if not isinstance(demos, Demonstrations):
        raise TypeError(f"fit expects Demonstrations, got {type(demos).__name__}")
    if demos.n_dims != 3:
        raise ValueError(f"hitting demonstrations must be 3-D, got {demos.n_dims}-D")
    if np.linalg.norm(demos.target) > 1e-12:
        raise ValueError("give the demonstrations relative to the ball with target=[0, 0, 0]")
    top = max(np.linalg.norm(v, axis=1).max() for v in demos.velocities)
    if arrival_speed(demos) <= 0.05 * top:
        raise ValueError(
            "the demonstrations' speed at the target is (nearly) zero: they stop at the ball "
            "instead of hitting it, so there is no hitting motion to learn")
    return demos


class HittingMotionLearner(BaseEstimator):
    """Learns a :class:`~seds_casadi.motion.hitting.HittingMotion` (scikit-learn estimator).

    Parameters
    ----------
    n_components : int, default 3
        Gaussians of the SEDS model (the paper used 3).
    strength_components : int, default 2
        Gaussians of the strength factor (the paper used 2).
    random_state : int, numpy Generator or None, default 0
        Seed of the first SEDS initialisation (k-means + EM); restarts use the next seeds.
        The strength factor's GMM uses it too.
    approach_ratio : float or None, default None
        If given, constrain the SEDS model so that the demonstrations' mean arrival direction
        is its slowest way into the ball, with sideways motion at least this many times faster
        (see :class:`~seds_casadi.SEDS`'s ``approach_direction``). Experimental.
    approach_paths : bool, default True
        Add virtual approach paths near the ball to the SEDS data so that swings line up with
        psi* before they reach it (module docstring); False: the paper's data only.
    approach_length, approach_order : float, default 0.1 and 3.0
        Length [m] of the approach paths and the order of their contact with the arrival line.
    restarts : int, default 3
        Initialisations tried at most when the probe check fails (1: no restart).
    max_direction_error : float, default 1.0
        Probe check threshold [deg]: every probe swing must hit with its direction within it.
    rest_length : float, default 0.2
        Distance [m] over which the resting mode stops the club after the hit.
    seds_params : dict or None, default None
        Further options of :class:`~seds_casadi.SEDS` (e.g. ``{"omega_upper": 3.0}``); the
        objective defaults to ``"direction"`` (Eq. 9).

    Attributes
    ----------
    motion_ : HittingMotion
        The learned motion.
    fit_info_ : dict
        The SEDS fits tried (seed, probe errors), which one was kept, whether approach paths
        were used, and the number of probe starts (also ``motion_.fit_info``).
    n_features_in_ : int
        3.
    """

    def __init__(self, n_components: int = 3, strength_components: int = 2, random_state=0,
                 approach_ratio: float | None = None, approach_paths: bool = True,
                 approach_length: float = 0.1, approach_order: float = 3.0, restarts: int = 3,
                 max_direction_error: float = 1.0, rest_length: float = 0.2,
                 seds_params: dict | None = None) -> None:
        # scikit-learn convention: store the parameters as given; fit() validates them
        self.n_components = n_components
        self.strength_components = strength_components
        self.random_state = random_state
        self.approach_ratio = approach_ratio
        self.approach_paths = approach_paths
        self.approach_length = approach_length
        self.approach_order = approach_order
        self.restarts = restarts
        self.max_direction_error = max_direction_error
        self.rest_length = rest_length
        self.seds_params = seds_params

    def _validated(self) -> dict:
        """The parameters checked (ValueError/TypeError with what to pass instead)."""
        K, r = self.n_components, self.restarts
        if isinstance(K, bool) or not isinstance(K, (int, np.integer)) or K < 1:
            raise ValueError(f"n_components must be a positive integer, got {K!r}")
        if isinstance(r, bool) or int(r) != r or r < 1:
            raise ValueError(f"restarts must be a positive integer, got {r!r}")
        e = self.max_direction_error
        if not (np.isfinite(e) and e > 0):
            raise ValueError(f"max_direction_error must be positive, got {e}")
        if not (np.isfinite(self.rest_length) and self.rest_length > 0):
            raise ValueError(f"rest_length must be positive, got {self.rest_length}")
        if self.seds_params is not None and not isinstance(self.seds_params, dict):
            raise TypeError(f"seds_params must be a dict of SEDS options, got "
                            f"{type(self.seds_params).__name__}")
        rs = self.random_state
        if isinstance(rs, np.random.Generator):
            seed0 = int(rs.integers(2**31 - 1))
            strength_rs = seed0
        else:
            seed0, strength_rs = (0 if rs is None else int(rs)), rs
        return {"restarts": int(r), "seed0": seed0, "strength_random_state": strength_rs}

    def _seds_options(self, approach: np.ndarray) -> dict:
        opts = dict(self.seds_params or {})
        opts.setdefault("objective", "direction")
        # the hitting DS has its own strength factor (Eq. 12, over the approach paths too) and
        # uses only the directions of f (Eq. 8): a plain GMM DS keeps its kernels lean
        opts.setdefault("speed_calibration", "median")
        if self.approach_ratio is not None:
            opts.setdefault("approach_direction", approach)
            opts.setdefault("approach_ratio", self.approach_ratio)
        return opts

    def _seds_data(self, demos: Demonstrations, approach: np.ndarray) -> Demonstrations:
        """The demonstrations, with the approach paths when asked for."""
        if not self.approach_paths:
            return demos
        P, V = approach_paths(approach, arrival_speed(demos), self.approach_length,
                              self.approach_order)
        return Demonstrations(list(demos.positions) + P, velocities=list(demos.velocities) + V,
                              target=np.zeros(3))

    def _fit_strength(self, demos: Demonstrations, random_state) -> StrengthFactor:
        """Eq. 12 on the demonstrations' samples that move (above 1e-3 of the top speed)."""
        X = np.concatenate(demos.positions)
        S = np.concatenate([np.linalg.norm(v, axis=1) for v in demos.velocities])
        keep = S > 1e-3 * S.max()
        return StrengthFactorLearner(self.strength_components, random_state).fit(
            X[keep], S[keep]).factor_

    def _try_seeds(self, data, approach, strength, starts, params) -> tuple[list, tuple | None]:
        """SEDS from successive seeds until the probe check passes: (tries, best), best =
        (worst probe error, motion, index of the try)."""
        opts = self._seds_options(approach)
        tries, best = [], None
        for i in range(params["restarts"]):
            seed = params["seed0"] + i
            try:
                ds = SEDS(int(self.n_components), random_state=seed, **opts).fit(data).model_
                motion = HittingMotion(TargetField(ds, approach=approach), strength,
                                       self.rest_length)
            except (ValueError, SEDSError) as exc:  # spiralling limit, certificate, solver
                tries.append({"seed": seed, "error": str(exc)})
                continue
            hit, err, _ = motion.probe(starts)
            worst = float(np.max(np.where(hit, err, 180.0)))
            tries.append({"seed": seed, "hits": int(hit.sum()), "probes": len(hit),
                          "max_direction_error_deg": worst,
                          "median_direction_error_deg": float(np.median(err[hit]))
                          if hit.any() else float("nan")})
            if best is None or worst < best[0]:
                best = (worst, motion, i)
            if worst <= self.max_direction_error:
                break
        return tries, best

    def fit(self, X, y=None) -> HittingMotionLearner:
        """Learn the target field (SEDS, direction objective) and the strength factor (GMR).

        Parameters
        ----------
        X : Demonstrations
            3-D club-head demonstrations ending at the ball, which must be the origin
            (``target=[0, 0, 0]``), with a non-zero speed there.
        y : None
            Unused (scikit-learn's signature).

        Returns
        -------
        self
            With ``motion_`` and ``fit_info_``.

        Raises
        ------
        SolverError
            No SEDS fit succeeded in ``restarts`` tries.
        """
        params = self._validated()
        demos = _check_demos(X)
        approach = arrival_direction(demos)
        data = self._seds_data(demos, approach)
        strength = self._fit_strength(demos, params["strength_random_state"])
        starts = probe_starts(demos)
        tries, best = self._try_seeds(data, approach, strength, starts, params)
        if best is None:
            raise SolverError(f"no SEDS fit succeeded in {params['restarts']} tries: "
                              + "; ".join(t["error"] for t in tries), "failed")
        worst, motion, kept = best
        if worst > self.max_direction_error:
            warnings.warn(
                f"after {len(tries)} SEDS fits the best hitting motion still arrives up to "
                f"{worst:.2f} deg off psi* from a probe start (asked: {self.max_direction_error}"
                " deg); try more restarts, another n_components, or approach_paths=True",
                ConvergenceWarning, stacklevel=2)
        motion.fit_info = {"tries": tries, "kept": kept,
                           "approach_paths": bool(self.approach_paths),
                           "probe_starts": len(starts)}
        self.motion_ = motion
        self.fit_info_ = motion.fit_info
        self.n_features_in_ = 3
        return self
