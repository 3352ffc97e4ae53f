"""The steerable hitting DS of the paper's Section 4 (Eq. 13-14), from a target field and a
strength factor.

    xdot = f_h(x) = v(x) h(x)                                   (Eq. 3)
    h(x) = f(x) / ||f(x)||,   h(x*) = lim_{x -> x*} h(x)         (Eq. 8,  target_field.py)
    v(x) = GMR of the speed on the position                      (Eq. 12, strength.py)
    v* = v(x*),  psi* = h(x*)                                    (Eq. 13)
    xdot = kappa R_alpha v(R_alpha^T x) h(R_alpha^T x)           (Eq. 14, here)

Positions are relative to the ball (x* = 0), z up; R_alpha turns about +z through the ball.

Eq. 14 is written once, as a CasADi expression (:func:`hitting_ds_sx`, built on the expressions of
Eq. 8 and Eq. 12); :meth:`HittingMotion.velocity` evaluates it over many points at once,
:meth:`HittingMotion.compiled` compiles it to C for the 500 Hz controller, and rollouts call it
point by point through a low-overhead evaluator. Learning a motion from demonstrations is
:class:`~seds_casadi.motion.learner.HittingMotionLearner` (:meth:`HittingMotion.fit` is a
shortcut); swings in time are in :mod:`seds_casadi.motion.rollout`, the resting mode after the
hit in :mod:`seds_casadi.motion.resting`.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence

import casadi as ca
import numpy as np

from ..codegen import CachedFunctionMixin, batch_evaluate
from ..core.demonstrations import Demonstrations
from ..core.errors import ModelFileError
from ..core.model_files import read_guarded, write_guarded
from ..core.stable_ds import StableDS
from . import rollout as _rollout
from ._validation import as_points, check_alpha_kappa
from .approach import approach_paths
from .resting import resting_system
from .rollout import RolloutResult
from .rotation import rotation_z, rotation_z_sx
from .strength import StrengthFactor
from .target_field import TargetField

# approach_paths, StrengthFactor, TargetField, RolloutResult and rotation_z are re-exported: they
# were defined here before the motion was split into one module per concept
__all__ = ["HittingMotion", "hitting_ds_sx", "TargetField", "StrengthFactor", "RolloutResult",
           "rotation_z", "approach_paths"]


#: the ``format`` of a motion's ``strength.npz`` (the guarded format of core.model_files)
STRENGTH_FORMAT = "seds_casadi.StrengthFactor"
_STRENGTH_SCHEMA = {"priors": 1, "means": 2, "covariances": 3, "log_range": 1, "approach": 1,
                    "rest_length": 0}

def hitting_ds_sx(x, alpha, kappa, target_field: TargetField, strength: StrengthFactor) -> ca.SX:
    """Eq. 14 as SX: kappa R_alpha v(R_alpha^T x) h(R_alpha^T x).

    Parameters
    ----------
    x : casadi.SX, shape (3, 1)
        Club-head position relative to the ball.
    alpha, kappa : casadi.SX scalars (or numbers)
        Hitting angle [rad] about +z and speed gain.
    target_field : TargetField
        h of Eq. 8 (:func:`~seds_casadi.motion.target_field.target_field_sx`).
    strength : StrengthFactor
        v of Eq. 12 (:func:`~seds_casadi.motion.strength.strength_sx`).

    Returns
    -------
    casadi.SX, shape (3, 1)
    """
    R = rotation_z_sx(alpha)
    y = R.T @ x
    return kappa * (R @ (strength.sx(y) * target_field.sx(y)))


class HittingMotion(CachedFunctionMixin):
    """The steerable hitting DS of Eq. 14, from a target field and a strength factor.

    A fitted value: build one from its parts, learn one with :meth:`fit` (or
    :class:`~seds_casadi.motion.learner.HittingMotionLearner`), or :meth:`load` a saved one.

    Parameters
    ----------
    target_field : TargetField
    strength : StrengthFactor
    rest_length : float
        Distance [m] over which the resting mode stops the club after the hit.

    Attributes
    ----------
    hitting_direction : array, shape (3,)
        psi* (Eq. 13).
    hitting_speed : float
        v* = v(x*) (Eq. 13).
    fit_info : dict
        For a learned motion: the SEDS fits tried, their probe errors and which one was kept.
    """

    def __init__(self, target_field: TargetField, strength: StrengthFactor,
                 rest_length: float = 0.2) -> None:
        if target_field.ds.n_dims != 3 or strength.n_dims != 3:
            raise ValueError("the hitting motion is defined in 3-D (club-head position)")
        if np.linalg.norm(target_field.ds.target) > 1e-12:
            raise ValueError("the hitting motion needs its StableDS fitted with the ball at the "
                             "origin (target=[0, 0, 0])")
        if not (np.isfinite(rest_length) and rest_length > 0):
            raise ValueError(f"rest_length must be positive, got {rest_length}")
        self.target_field = target_field
        self.strength = strength
        self.rest_length = float(rest_length)
        self.hitting_direction = target_field.hitting_direction.copy()
        self.hitting_speed = float(strength(np.zeros(3)))
        self.fit_info: dict = {}

    @classmethod
    def fit(cls, demos: Demonstrations, n_components: int = 3, strength_components: int = 2,
            random_state=0, approach_ratio: float | None = None, approach_paths: bool = True,
            approach_length: float = 0.1, approach_order: float = 3.0, restarts: int = 3,
            max_direction_error: float = 1.0, **seds_kwargs) -> HittingMotion:
        """Learn a hitting motion: a shortcut for
        ``HittingMotionLearner(n_components, ..., seds_params=seds_kwargs).fit(demos).motion_``.

        The parameters are those of :class:`~seds_casadi.motion.learner.HittingMotionLearner`
        (``**seds_kwargs`` is its ``seds_params``: options of :class:`~seds_casadi.SEDS` such as
        ``omega_upper``). ``motion.fit_info`` records the SEDS fits tried: seed, probe errors,
        and which model was kept.
        """
        from .learner import HittingMotionLearner

        return HittingMotionLearner(
            n_components=n_components, strength_components=strength_components,
            random_state=random_state, approach_ratio=approach_ratio,
            approach_paths=approach_paths, approach_length=approach_length,
            approach_order=approach_order, restarts=restarts,
            max_direction_error=max_direction_error, seds_params=seds_kwargs or None,
        ).fit(demos).motion_

    # ------------------------------------------------------------ swings
    def probe(self, starts, alpha: float = 0.0, kappa: float = 1.0, dt: float = 0.002,
              max_time: float = 5.0, hit_radius: float = 0.02
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Swings from many starts at once (ball fixed at the origin, no perturbation).

        The same integration and hit reading as :meth:`rollout` (explicit Euler at ``dt``, hit
        at the crossing of the plane through the ball perpendicular to R_alpha psi* within
        ``hit_radius``, hitting velocity = mean velocity over the last period), vectorised.

        Returns
        -------
        hit : bool array, shape (n,)
        direction_error : array, shape (n,)
            Angle [deg] between the hitting velocity and R_alpha psi* (NaN without a hit).
        speed_error : array, shape (n,)
            Relative error of the hitting speed against kappa v* (NaN without a hit).
        """
        return _rollout.probe(self, starts, alpha, kappa, dt, max_time, hit_radius)

    def rollout(self, start, alpha: float = 0.0, kappa: float = 1.0, dt: float = 0.002,
                ball=None, perturb: Sequence[dict] | None = None, max_time: float = 5.0,
                rest_mode: str = "flat", rest_time: float = 0.5,
                params: Callable | None = None, hit_radius: float = 0.02,
                hole=None) -> RolloutResult:
        """Integrate a swing from ``start`` until the club hits the ball, then rest.

        Parameters
        ----------
        start : array, shape (3,)
            Club-head start in the field frame.
        alpha, kappa : float
            Hitting angle [rad] and speed gain.
        dt : float
            Step [s] (500 Hz by default, the controller's rate).
        ball : array, shape (3,), optional
            Ball position in the field frame (default: the origin).
        perturb : list of dict, optional
            Changes applied on the fly at given times, no re-planning: each dict has ``t`` [s]
            and any of ``ball`` (new position), ``hole`` (new position, read by ``params``),
            ``alpha``, ``kappa``.
        max_time : float
            Give up (no hit) after this time.
        rest_mode : {"flat", "arc"}
        rest_time : float
            How long to integrate the resting mode after the hit.
        params : callable, optional
            ``params(t, ball, hole) -> (alpha [rad], kappa)`` evaluated every step (e.g. a
            hitting-parameter model reacting to a moving hole; the same signature as
            :func:`seds_casadi.robots.simulate_swing`'s); overrides alpha and kappa.
        hit_radius : float
            The club hits the ball when it crosses the plane through the ball perpendicular to
            the commanded hitting direction within this distance [m] of the ball's centre.
        hole : array, shape (2,) or (3,), optional
            The hole, handed to ``params``.
        """
        return _rollout.rollout(self, start, alpha, kappa, dt, ball, perturb, max_time,
                                rest_mode, rest_time, params, hit_radius, hole)

    # ------------------------------------------------------------ persistence
    def save(self, folder: str | os.PathLike) -> None:
        """Write the motion into ``folder``: ``stable_ds.npz`` (the certified SEDS model, with
        its checksum) and ``strength.npz`` (strength factor, approach direction, rest length);
        no pickle."""
        folder = os.fspath(folder)
        os.makedirs(folder, exist_ok=True)
        self.target_field.ds.save(os.path.join(folder, "stable_ds.npz"))
        s = self.strength
        write_guarded(os.path.join(folder, "strength.npz"), STRENGTH_FORMAT, 1,
                      {"priors": s.priors, "means": s.means, "covariances": s.covariances,
                       "log_range": np.array(s.log_range, float),
                       "approach": np.asarray(self.target_field.approach, float),
                       "rest_length": np.array(float(self.rest_length))})

    @classmethod
    def load(cls, folder: str | os.PathLike) -> HittingMotion:
        """Read a motion written by :meth:`save`: both files are checked (format, version,
        checksum, types), the SEDS model is re-certified, and the strength factor's GMM and
        ranges are validated; anything wrong raises :class:`~seds_casadi.ModelFileError`."""
        folder = os.fspath(folder)
        ds = StableDS.load(os.path.join(folder, "stable_ds.npz"))
        path = os.path.join(folder, "strength.npz")
        a, _, _ = read_guarded(path, STRENGTH_FORMAT, (1,), _STRENGTH_SCHEMA)
        d = ds.n_dims
        K = len(a["priors"])
        ok = (a["means"].shape == (K, d + 1) and a["covariances"].shape == (K, d + 1, d + 1)
              and a["log_range"].shape == (2,) and a["approach"].shape in ((d,), (0,))
              and a["rest_length"].shape == ())
        if not ok:
            raise ModelFileError(f"{path}: array shapes do not fit a {d}-D strength factor")
        if np.any(a["priors"] <= 0) or abs(float(a["priors"].sum()) - 1.0) > 1e-9:
            raise ModelFileError(f"{path}: the priors are not positive or do not sum to 1")
        if not (a["log_range"][0] <= a["log_range"][1] and a["rest_length"] > 0):
            raise ModelFileError(f"{path}: log_range or rest_length out of range")
        try:
            for c in a["covariances"]:
                np.linalg.cholesky(c)
        except np.linalg.LinAlgError:
            raise ModelFileError(f"{path}: a covariance is not positive definite") from None
        strength = StrengthFactor(a["priors"], a["means"], a["covariances"],
                                  tuple(a["log_range"]))
        return cls(TargetField(ds, approach=a["approach"] if a["approach"].size == d else None),
                   strength, float(a["rest_length"]))

    # ------------------------------------------------------------ evaluation
    def velocity(self, X, alpha: float = 0.0, kappa: float = 1.0) -> np.ndarray:
        """Eq. 14: kappa R_alpha v(R_alpha^T x) h(R_alpha^T x), x relative to the ball
        (the expression of :meth:`to_casadi`, evaluated over all points at once).

        Parameters
        ----------
        X : array, shape (n, 3) or (3,)
        alpha : float
            Hitting angle [rad] about +z.
        kappa : float
            Speed gain (> 0).

        Returns
        -------
        array, same shape as X
        """
        alpha, kappa = check_alpha_kappa(alpha, kappa)
        X2, single = as_points(X, 3)
        if len(X2) == 0:
            return X2.copy()
        out = batch_evaluate(self._function(), X2.T, alpha, kappa)[0]
        return out[0] if single else out

    def commanded_direction(self, alpha: float = 0.0) -> np.ndarray:
        """The commanded hitting direction R_alpha psi* (Eq. 13-14), shape (3,)."""
        return rotation_z(alpha) @ self.hitting_direction

    def hitting_velocity(self, alpha: float = 0.0, kappa: float = 1.0) -> np.ndarray:
        """The commanded velocity at the ball, kappa v* R_alpha psi* (Eq. 13-14)."""
        alpha, kappa = check_alpha_kappa(alpha, kappa)
        return kappa * self.hitting_speed * self.commanded_direction(alpha)

    def resting_velocity(self, X, hit_position, hit_velocity, mode: str = "flat") -> np.ndarray:
        """The resting-mode DS after the hit (:mod:`seds_casadi.motion.resting`).

        Parameters
        ----------
        X : array, shape (n, 3) or (3,)
        hit_position, hit_velocity : array, shape (3,)
        mode : {"flat", "arc"}
        """
        X2, single = as_points(X, 3)
        A, rest = self._rest_system(np.asarray(hit_position, float),
                                    np.asarray(hit_velocity, float), mode)
        out = (X2 - rest) @ A.T
        return out[0] if single else out

    def _rest_system(self, p_hit, v_hit, mode):
        """A_r and x_r of the resting mode with this motion's rest length
        (:func:`~seds_casadi.motion.resting.resting_system`)."""
        return resting_system(p_hit, v_hit, self.rest_length, mode)

    # ------------------------------------------------------------ CasADi
    def compiled(self):
        """Eq. 14 compiled to C and called through fixed buffers, for a real-time loop.

        Returns a callable ``(x, alpha, kappa) -> xdot`` (x of shape (3,), relative to the ball),
        about 2 us per call; it falls back to CasADi's virtual machine without a C compiler.
        Not thread-safe.
        """
        from ..codegen import FastEvaluator, compile_functions

        return FastEvaluator(compile_functions([self.to_casadi()])[0])

    def to_casadi(self, name: str = "hitting_ds") -> ca.Function:
        """Eq. 14 as a CasADi Function (x (3,), alpha, kappa) -> xdot (3,) (:func:`hitting_ds_sx`),
        for code generation; the one definition that every evaluation uses.

        Near the ball (||f|| below 1e-200) the target field takes its limit psi*.
        """
        x = ca.SX.sym("x", 3)
        alpha = ca.SX.sym("alpha")
        kappa = ca.SX.sym("kappa")
        xdot = hitting_ds_sx(x, alpha, kappa, self.target_field, self.strength)
        return ca.Function(name, [x, alpha, kappa], [xdot], ["x", "alpha", "kappa"], ["xdot"])

