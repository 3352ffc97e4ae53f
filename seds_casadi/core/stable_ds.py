"""The fitted, certified stable dynamical system f(x) of paper Eq. 5-7.

A :class:`StableDS` holds a GMM over the joint space (x, xdot) as plain arrays and evaluates

    f(x) = sum_k h^k(x) (mu_xdot^k + Sigma_xdotx^k (Sigma_x^k)^-1 (x - mu_x^k))      (Eq. 5)

with h^k the posterior weights of Eq. 6 (computed by log-sum-exp, so it is finite everywhere).
Every StableDS is certified against Eq. 10 when it is made (fitted, constructed or loaded).

Saved-model format (``.npz``, read with ``allow_pickle=False``)
----------------------------------------------------------------
``format`` = "seds_casadi.StableDS", ``version`` = 1, ``priors`` (K,), ``means`` (K, 2d),
``covariances`` (K, 2d, 2d), ``target`` (d,), ``fit_info`` (a JSON string) and ``checksum``: the
SHA-256 of the float64 little-endian bytes of priors, means, covariances and target followed by the
UTF-8 bytes of fit_info. ``load`` checks all of it and re-certifies stability.

A model with a learned Lyapunov matrix (issue 14) is written as ``version`` = 2 with the extra
entry ``lyapunov`` (d, d) after ``target`` (and in the checksum); it is certified against
A_k^T P + P A_k < 0 on load, so a tampered P is refused. Version 1 files load with P = I.

A model with a strength factor (``SEDS(speed_calibration="strength")``) is written as
``version`` = 3 (P = I) or 4 (learned P, ``lyapunov`` first) with the extra entries
``strength_priors`` (K_v,), ``strength_means`` (K_v, d+1), ``strength_covariances``
(K_v, d+1, d+1), ``strength_log_range`` (2,) and ``strength_radius`` (1,), in that order, in the
checksum too.
"""

from __future__ import annotations

import os
import warnings

import casadi as ca
import numpy as np

from ..codegen import CachedFunctionMixin, batch_evaluate
from ._io import read_npz
from .demonstrations import MAX_MAGNITUDE
from .errors import ConvergenceWarning, ModelFileError, StabilityError
from .gmm import responsibilities_sx
from .model_files import MAX_VALUES, RESERVED_BYTES, read_guarded, write_guarded
from .strength import StrengthFactor, as_points

FORMAT = "seds_casadi.StableDS"
VERSION = 1
VERSION_LYAPUNOV = 2
_SCHEMA = {"priors": 1, "means": 2, "covariances": 3, "target": 1}
_SCHEMA_LYAPUNOV = {**_SCHEMA, "lyapunov": 2}
VERSION_STRENGTH = 3
VERSION_STRENGTH_LYAPUNOV = 4
_STRENGTH_ENTRIES = {"strength_priors": 1, "strength_means": 2, "strength_covariances": 3,
                     "strength_log_range": 1, "strength_radius": 1}
_SCHEMAS = {VERSION: _SCHEMA, VERSION_LYAPUNOV: _SCHEMA_LYAPUNOV,
            VERSION_STRENGTH: {**_SCHEMA, **_STRENGTH_ENTRIES},
            VERSION_STRENGTH_LYAPUNOV: {**_SCHEMA_LYAPUNOV, **_STRENGTH_ENTRIES}}
#: beyond this many times the data's extent, Eq. 6 is evaluated at that distance (velocity_sx)
FAR_FACTOR = 1e6
#: most components (of the DS, and of its strength factor) and dimensions a model file may
#: declare: checked before the model is built (200,000 components took minutes to load)
MAX_FILE_COMPONENTS = 1000
MAX_FILE_DIMS = 100
#: below this ||f|| (only at x* in practice) a strength model's velocity is 0
_TINY = 1e-200
#: largest stable step of explicit Euler and RK4 for a rate lambda: dt * lambda below these
_STABLE_STEP = {"euler": 2.0, "rk4": 2.78}


def _distances(E: np.ndarray) -> np.ndarray:
    """Euclidean norm of each row, without overflow for rows beyond 1e154."""
    scale = np.max(np.abs(E), axis=1, keepdims=True)
    scale = np.where(scale > 0, scale, 1.0)
    with np.errstate(over="ignore"):  # inf only beyond the largest float
        return scale[:, 0] * np.linalg.norm(E / scale, axis=1)


def _real(value, name: str) -> float:
    """``value`` as a float if it is a real number (not a boolean, a string or an array)."""
    a = np.asarray(value)
    if a.shape != () or a.dtype.kind not in "iuf":
        raise TypeError(f"{name} must be a number, got {value!r}")
    return float(a)


def _finite(X: np.ndarray, starts: np.ndarray, step: int) -> np.ndarray:
    """``X`` if every entry is finite; else a ValueError naming the starts whose state left the
    floating-point range."""
    bad = ~np.all(np.isfinite(X), axis=1)
    if bad.any():
        raise ValueError(
            f"the rollout from start(s) {starts[bad][:10].tolist()} left the range of "
            f"floating-point numbers at step {step} (the velocity there overflows): start "
            "nearer the target or use a smaller dt")
    return X


def certify(
    priors: np.ndarray,
    means: np.ndarray,
    covariances: np.ndarray,
    target: np.ndarray,
    status: str = "unknown",
    rtol: float = 1e-8,
    lyapunov: np.ndarray | None = None,
) -> dict[str, float]:
    """Check the stability conditions of Eq. 10 numerically; raise if one fails.

    Condition (b) is checked in its generalised form A_k^T P + P A_k < 0 when a Lyapunov
    matrix P is given (then V(x) = (x - x*)^T P (x - x*) decreases along every trajectory), and
    as A_k + A_k^T < 0 (P = I, SEDS's V) otherwise.

    Parameters
    ----------
    priors : array, shape (K,)
    means : array, shape (K, 2d)
    covariances : array, shape (K, 2d, 2d)
    target : array, shape (d,)
    status : str
        Solver status to carry in the exception.
    rtol : float
        Relative tolerance for the equalities (e) and (a).
    lyapunov : array, shape (d, d), optional
        P, symmetric positive definite (checked).

    Returns
    -------
    dict
        The margins: ``max_eig_lyapunov`` (largest eigenvalue of any A_k^T P + P A_k, must be
        < 0), ``max_eig_sym_A`` (the same for P = I; may be >= 0 with a learned P),
        ``lyapunov_condition`` (cond(P)),
        ``min_eig_cov`` (smallest eigenvalue of any joint covariance, > 0), ``prior_sum_error``
        and ``f_target_norm`` (||f(x*)||, relative to the velocity scale of the means).

    Raises
    ------
    StabilityError
        Naming the violated constraint.
    """
    K = len(priors)
    d = len(target)
    if not (np.all(np.isfinite(priors)) and np.all(np.isfinite(means))
            and np.all(np.isfinite(covariances)) and np.all(np.isfinite(target))):
        raise StabilityError("the model has non-finite parameters", "finite parameters", status)
    # the bound on demonstrations (positions and velocities within MAX_MAGNITUDE): a model of
    # such data has its means and target within it and its covariances within its square;
    # beyond, its distances overflow (a model file's means at 1e300 predicted NaN everywhere)
    big = max(float(np.max(np.abs(means), initial=0.0)), float(np.max(np.abs(target),
                                                                       initial=0.0)))
    if big > MAX_MAGNITUDE or float(np.max(np.abs(covariances), initial=0.0)) > \
            MAX_MAGNITUDE ** 2:
        raise StabilityError(
            f"the model's means or target reach {big:.3g} or its covariances "
            f"{float(np.max(np.abs(covariances), initial=0.0)):.3g}: beyond the "
            f"{MAX_MAGNITUDE:.0e} (and its square) of any positions and velocities",
            "finite parameters", status)
    # (d), (e)
    if np.any(priors <= 0) or np.any(priors > 1 + 1e-12):
        raise StabilityError(f"priors {priors} outside (0, 1]", "(d) 0 < pi_k <= 1", status)
    psum = abs(float(np.sum(priors)) - 1.0)
    if psum > 1e-9:
        raise StabilityError(f"priors sum to {np.sum(priors)}", "(e) sum pi_k = 1", status)
    # (c)
    min_eig = np.inf
    for k in range(K):
        S = covariances[k]
        if np.max(np.abs(S - S.T)) > 1e-9 * max(1.0, np.max(np.abs(S))):
            raise StabilityError(f"covariance {k} is not symmetric", "(c) Sigma_k > 0", status)
        ev = np.linalg.eigvalsh(S)
        min_eig = min(min_eig, float(ev[0]))
        if ev[0] <= 0:
            raise StabilityError(
                f"joint covariance {k} is not positive definite (smallest eigenvalue {ev[0]:.3g})",
                "(c) Sigma_k > 0", status)
    # (b)
    P = _check_lyapunov(lyapunov, d, status)
    max_eig = max_sym = -np.inf
    f_err = 0.0
    for k in range(K):
        Sx = covariances[k][:d, :d]
        Sdx = covariances[k][d:, :d]
        A = np.linalg.solve(Sx.T, Sdx.T).T
        max_sym = max(max_sym, float(np.linalg.eigvalsh(A + A.T)[-1]))
        ev = np.linalg.eigvalsh(A.T @ P + P @ A)
        max_eig = max(max_eig, float(ev[-1]))
        if ev[-1] >= 0:
            cond = "(b) A_k + A_k^T < 0" if lyapunov is None else "(b) A_k^T P + P A_k < 0"
            raise StabilityError(
                f"component {k}: {cond[4:-4]} has eigenvalue {ev[-1]:.3g} >= 0", cond, status)
        # (a): mu_xdot + A (x* - mu_x) = 0
        resid = means[k, d:] + A @ (target - means[k, :d])
        scale = max(np.linalg.norm(means[k, d:]), np.linalg.norm(A) * np.linalg.norm(
            target - means[k, :d]), 1e-300)
        f_err = max(f_err, float(np.linalg.norm(resid) / scale))
        if np.linalg.norm(resid) > rtol * scale and np.linalg.norm(resid) > 1e-12:
            raise StabilityError(
                f"component {k}: its linear model does not vanish at the target "
                f"(residual {np.linalg.norm(resid):.3g})", "(a) f(x*) = 0", status)
    return {"max_eig_lyapunov": max_eig, "max_eig_sym_A": max_sym,
            "lyapunov_condition": float(np.linalg.cond(P)), "min_eig_cov": min_eig,
            "prior_sum_error": psum, "f_target_norm": f_err}


def _check_lyapunov(P, d: int, status: str) -> np.ndarray:
    """P as a checked (d, d) symmetric positive definite array (the identity for None)."""
    if P is None:
        return np.eye(d)
    P = np.asarray(P, dtype=float)
    if P.shape != (d, d):
        raise StabilityError(f"the Lyapunov matrix has shape {P.shape}, not ({d}, {d})",
                             "P > 0", status)
    if not np.all(np.isfinite(P)) or np.max(np.abs(P - P.T)) > 1e-9 * max(1.0, np.abs(P).max()):
        raise StabilityError("the Lyapunov matrix is not a finite symmetric matrix", "P > 0",
                             status)
    ev = np.linalg.eigvalsh(P)
    if ev[0] <= 1e-12 * ev[-1]:
        raise StabilityError(f"the Lyapunov matrix is not positive definite (eigenvalues "
                             f"{ev[0]:.3g} .. {ev[-1]:.3g})", "P > 0", status)
    return P


class StableDS(CachedFunctionMixin):
    """A globally asymptotically stable GMM dynamical system (Eq. 5-7), certified by Eq. 10.

    Parameters
    ----------
    priors : array, shape (K,)
    means : array, shape (K, 2d)
        Joint means (mu_x, mu_xdot) in the demonstrations' coordinates.
    covariances : array, shape (K, 2d, 2d)
        Joint covariances [[Sigma_x, Sigma_xxdot], [Sigma_xdotx, Sigma_xdot]].
    target : array, shape (d,)
        The attractor x*.
    fit_info : dict, optional
        Solver report (``status``, ``iterations``, ``objective``, ``seconds``, ...).
    status : str
        Status carried by a :class:`StabilityError` if the certificate fails.
    lyapunov : array, shape (d, d), optional
        The matrix P of V(x) = (x - x*)^T P (x - x*) that certifies the model (a learned one,
        ``SEDS(lyapunov="learned")``); None for SEDS's P = I.
    strength : StrengthFactor, optional
        A strength factor v(x) > 0 (Eq. 12, :class:`~seds_casadi.core.strength.StrengthFactor`)
        over the same positions. The model then moves along the streamlines of the Eq. 5 system
        at the speed v: ``predict`` returns

            f_v(x) = v(x) rho(x) f(x) / ||f(x)||,   rho(x) = ||x - x*|| / sqrt(||x - x*||^2 + r^2)

        (Eq. 3 with the target field of Eq. 8 and the strength factor of Eq. 12), where rho
        tapers the speed within about r of the target so that x* is reached smoothly
        (exponentially, at the rate v(x*) / r) instead of chattering across it. f_v is a
        positive multiple of f away from x*, so the same streamlines, the same certificate and
        the same Lyapunov function hold: V decreases along every trajectory of f_v wherever it
        does along f. ``gains_velocity_sx`` is f itself.
    strength_radius : float, optional
        r of the taper (required with ``strength``; in position units, > 0).

    Attributes
    ----------
    A : array, shape (K, d, d)
        A_k = Sigma_xdotx^k (Sigma_x^k)^-1.
    certificate : dict
        Margins returned by :func:`certify`.
    """

    def __init__(self, priors, means, covariances, target, fit_info=None, status="constructed",
                 lyapunov=None, strength: StrengthFactor | None = None,
                 strength_radius: float | None = None):
        self.priors = np.array(priors, dtype=float).ravel()
        self.means = np.array(means, dtype=float)
        self.covariances = np.array(covariances, dtype=float)
        self.target = np.array(target, dtype=float).ravel()
        K, d = len(self.priors), len(self.target)
        if self.means.shape != (K, 2 * d) or self.covariances.shape != (K, 2 * d, 2 * d):
            raise ValueError(
                f"inconsistent shapes: priors {self.priors.shape}, means {self.means.shape}, "
                f"covariances {self.covariances.shape}, target {self.target.shape}; expected "
                f"({K},), ({K}, {2 * d}), ({K}, {2 * d}, {2 * d}), ({d},)"
            )
        self._lyapunov = None if lyapunov is None else np.array(lyapunov, dtype=float)
        self.certificate = certify(self.priors, self.means, self.covariances, self.target, status,
                                   lyapunov=self._lyapunov)
        self.A = np.stack([
            np.linalg.solve(self.covariances[k, :d, :d].T, self.covariances[k, d:, :d].T).T
            for k in range(K)
        ])
        if fit_info is not None and not isinstance(fit_info, dict):
            raise TypeError(f"fit_info must be a dict (the fit's report), got "
                            f"{type(fit_info).__name__}")
        self.fit_info = dict(fit_info or {})
        self.strength, self.strength_radius = _check_strength(strength, strength_radius, d)

    @property
    def lyapunov_matrix(self) -> np.ndarray:
        """P of the certificate V(x) = (x - x*)^T P (x - x*): learned, or the identity (SEDS)."""
        return np.eye(self.n_dims) if self._lyapunov is None else self._lyapunov.copy()

    @property
    def n_components(self) -> int:
        """Number of Gaussians K."""
        return len(self.priors)

    @property
    def n_dims(self) -> int:
        """State dimension d."""
        return len(self.target)

    # ------------------------------------------------------------ evaluation
    def predict(self, X) -> np.ndarray:
        """Velocity f(x) of Eq. 5 at each point (the expression of :meth:`to_casadi`; with a
        strength factor, f_v(x) of the class docstring).

        Parameters
        ----------
        X : array, shape (n, d) or (d,)

        Returns
        -------
        array, same shape as X
        """
        X2, single = as_points(X, self.n_dims)
        if len(X2) == 0:
            return X2.copy()
        F = batch_evaluate(self._function(), X2.T)[0]
        return F[0] if single else F

    def rollout(self, x0, dt: float, max_steps: int = 20000, tol: float | None = None,
                method: str = "rk4", return_info: bool = False, warn: bool = True):
        """Integrate xdot = f(x) from one or several starts until they reach the target.

        Parameters
        ----------
        x0 : array, shape (d,) or (m, d)
        dt : float
            Time step [s].
        max_steps : int
            Upper bound on the steps.
        tol : float, optional
            Stop a trajectory once ||x - x*|| < tol. Default: 1e-3 times the largest start distance.
        method : {"rk4", "euler"}
        return_info : bool
            Also return a dict: ``converged`` (bool per start), ``steps`` (steps taken per start)
            and ``final_distance`` (||x - x*|| at the end of each trajectory).
        warn : bool
            Give a :class:`~seds_casadi.ConvergenceWarning` naming the starts that did not reach
            the target within ``max_steps`` (a rollout never stops silently at its step limit).

        Returns
        -------
        paths : array, shape (T, d) for one start, or a list of such arrays (each ends when it
            reached the target, or at ``max_steps``)
        info : dict, only with ``return_info``
        """
        X, single = as_points(x0, self.n_dims, "x0")
        dt = _real(dt, "dt")
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be positive, got {dt}")
        if tol is not None and not (np.isfinite(tol := _real(tol, "tol")) and tol >= 0):
            raise ValueError(f"tol must be a finite distance >= 0 (or None: 1e-3 times the "
                             f"largest start distance), got {tol}; a trajectory stops once "
                             "||x - x*|| < tol")
        steps = np.asarray(max_steps)
        if steps.shape != () or steps.dtype.kind not in "iu" or steps < 0:
            raise ValueError(f"max_steps must be a whole number >= 0, got {max_steps!r}")
        if method not in ("rk4", "euler"):
            raise ValueError(f"unknown method {method!r}; valid: rk4, euler")
        rate = self.stiffness() if warn else 0.0
        if dt * rate >= _STABLE_STEP[method]:
            warnings.warn(
                f"{method} at dt = {dt:g} s cannot follow this model's stiffest component (rate "
                f"{rate:.3g}/s; stable only for dt < {_STABLE_STEP[method] / rate:.3g} s): "
                "the rollout may oscillate or diverge. Use a smaller dt"
                + (", method='rk4'," if method != "rk4" else "")
                + " or fit with SEDS(gain_limit=...)", ConvergenceWarning, stacklevel=2)
        dist0 = _distances(X - self.target)
        if tol is None:
            tol = 1e-3 * max(float(dist0.max()), 1e-12)
        traj = [X.copy()]
        done = dist0 < tol
        end = np.where(done, 0, -1)
        x = X.copy()
        for step in range(1, int(max_steps) + 1):
            if done.all():
                break
            a = ~done
            xa = x[a]
            with np.errstate(over="ignore", invalid="ignore"):
                if method == "euler":
                    xa = xa + dt * self.predict(xa)
                else:
                    k1 = self.predict(xa)
                    k2 = self.predict(_finite(xa + 0.5 * dt * k1, np.flatnonzero(a), step))
                    k3 = self.predict(_finite(xa + 0.5 * dt * k2, np.flatnonzero(a), step))
                    k4 = self.predict(_finite(xa + dt * k3, np.flatnonzero(a), step))
                    xa = xa + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
            x = x.copy()
            x[a] = _finite(xa, np.flatnonzero(a), step)
            traj.append(x)
            newly = a & (_distances(x - self.target) < tol)
            end[newly] = step
            done |= newly
        T = np.stack(traj)
        outs = [T[: (e if e >= 0 else len(T) - 1) + 1, i] for i, e in enumerate(end)]
        info = {"converged": end >= 0, "steps": np.where(end >= 0, end, len(T) - 1),
                "final_distance": _distances(x - self.target)}
        if warn and not info["converged"].all():
            bad = np.flatnonzero(~info["converged"])
            warnings.warn(
                f"{len(bad)} of {len(X)} rollout(s) did not reach the target (within {tol:.3g}) "
                f"in {int(max_steps)} steps of {dt:g} s: start(s) {bad[:10].tolist()} end "
                f"{info['final_distance'][bad].max():.3g} away; raise max_steps or dt, or check "
                "the model's speed (fit_info['speed_factor'])", ConvergenceWarning, stacklevel=2)
        paths = outs[0] if single else outs
        return (paths, info) if return_info else paths

    def velocity_sx(self, x) -> ca.SX:
        """The model's velocity as an SX expression of a symbolic point x (shape (d, 1)).

        Eq. 5 (:meth:`gains_velocity_sx`); with a strength factor, f_v(x) = v(x) rho(x)
        f(x) / ||f(x)|| (class docstring; 0 at x*).
        """
        f = self.gains_velocity_sx(x)
        if self.strength is None:
            return f
        e2 = ca.sumsqr(x - ca.DM(self.target))
        rho = ca.sqrt(e2 / (e2 + self.strength_radius ** 2))
        nf = ca.norm_2(f)
        near = (self.strength.sx(x) * rho / ca.fmax(nf, _TINY)) * f
        # beyond the far radius of gains_velocity_sx the weights are those at the pulled-back
        # point y and f is linear in x - x*, so f(y) has f(x)'s direction without its overflow
        # (||f(x)||^2 and ||x - x*||^2 overflow from about 1e154: inf / inf); rho is 1 there to
        # 1e-12
        R = self._far_radius()
        e = x - ca.DM(self.target)
        far = ca.mmax(ca.fabs(e))
        fy = self.gains_velocity_sx(ca.DM(self.target) + (R / ca.fmax(far, R)) * e)
        far_v = (self.strength.sx(x) / ca.fmax(ca.norm_2(fy), _TINY)) * fy
        return ca.if_else(far > R, far_v, near)

    def gains_velocity_sx(self, x) -> ca.SX:
        """Eq. 5 as an SX expression of a symbolic point x (shape (d, 1)): the one definition.

        f(x) = sum_k h^k(x) (mu_xdot^k + A_k (x - mu_x^k)), h^k of Eq. 6. The model is certified,
        so Eq. 10a holds (mu_xdot^k = A_k (mu_x^k - x*)) and this is written as
        f(x) = sum_k h^k(x) A_k (x - x*): equal, and free of cancellation near x*, where the
        target field (Eq. 8) divides by ||f||.
        """
        d = self.n_dims
        e = x - ca.DM(self.target)
        # far from the data (beyond FAR_FACTOR times its extent) the weights are taken at the
        # point pulled radially back to that distance: the Gaussians' exponents would overflow
        # (NaN from inf - inf at 1e200) while the weights there already depend only on the
        # direction; the expression is unchanged within that distance
        R = self._far_radius()
        far = ca.mmax(ca.fabs(e))
        s = R / ca.fmax(far, R)  # max-norm: no overflow, no 0/0 at x*
        h = responsibilities_sx(ca.DM(self.target) + s * e, self.priors, self.means[:, :d],
                                self.covariances[:, :d, :d])
        # the gains act on e / c (entries within 1) and the sum is scaled back by c: where
        # f(x) is beyond the largest float it is +-inf, not NaN (A_k e summed +inf and -inf
        # terms from about 1e308); c = 1 within distance 1 of x*, where nothing changes
        c = ca.fmax(far, 1.0)
        f = ca.SX.zeros(d, 1)
        for k in range(self.n_components):
            f = f + h[k] * (ca.DM(self.A[k]) @ (e / c))
        return c * f

    def _far_radius(self) -> float:
        """FAR_FACTOR times the data's extent: the largest distance of a component's mean
        from the target plus its standard deviation."""
        d = self.n_dims
        ext = max(float(np.linalg.norm(self.means[k, :d] - self.target)
                        + np.sqrt(np.trace(self.covariances[k, :d, :d])))
                  for k in range(self.n_components))
        return FAR_FACTOR * max(ext, 1e-300)

    def stiffness(self) -> float:
        """The largest |eigenvalue| of any A_k [1/s]: explicit Euler needs dt < 2 / stiffness,
        RK4 dt < 2.78 / stiffness, to follow the model near that component.

        With a strength factor: the largest spectral radius of the Jacobian of f_v at points
        around the target (at r / 2, where the taper's rate v(x*) / r acts) and at the
        components' means: a sample, not a bound. Where ||f|| is small away from the target
        the direction f / ||f|| turns quickly (its Jacobian grows as ||grad f|| / ||f||), so a
        strength model can be stiffer there than this figure; the plain model crawls in the
        same places."""
        if self.strength is None:
            return float(max(np.abs(np.linalg.eigvals(A)).max() for A in self.A))
        cached = self.__dict__.get("_stiffness")
        if cached is None:
            d = self.n_dims
            x = ca.SX.sym("x", d)
            jac = ca.Function("seds_f_jacobian", [x], [ca.jacobian(self.velocity_sx(x), x)])
            eye = np.eye(d)
            pts = np.vstack([self.target + 0.5 * self.strength_radius * np.r_[eye, -eye],
                             self.means[:, :d]])
            cached = self.__dict__["_stiffness"] = float(max(
                np.abs(np.linalg.eigvals(np.asarray(jac(p)))).max() for p in pts))
        return cached

    def to_casadi(self, name: str = "seds_f") -> ca.Function:
        """Eq. 5 (:meth:`velocity_sx`) as a CasADi Function x (d,) -> f(x) (d,), for code
        generation or optimal control; :meth:`predict` evaluates it."""
        x = ca.SX.sym("x", self.n_dims)
        return ca.Function(name, [x], [self.velocity_sx(x)], ["x"], ["xdot"])

    # ------------------------------------------------------------ persistence
    def save(self, path: str | os.PathLike) -> None:
        """Write the model to ``path`` (``.npz``, the guarded format of
        :mod:`seds_casadi.core.model_files`: checksum, no pickle), atomically."""
        arrays = {"priors": self.priors, "means": self.means,
                  "covariances": self.covariances, "target": self.target}
        version = VERSION
        if self._lyapunov is not None:
            arrays["lyapunov"] = self._lyapunov
            version = VERSION_LYAPUNOV
        if self.strength is not None:
            sf = self.strength
            arrays.update(strength_priors=sf.priors, strength_means=sf.means,
                          strength_covariances=sf.covariances,
                          strength_log_range=np.asarray(sf.log_range, dtype=float),
                          strength_radius=np.array([self.strength_radius]))
            version = (VERSION_STRENGTH_LYAPUNOV if self._lyapunov is not None
                       else VERSION_STRENGTH)
        write_guarded(path, FORMAT, version, arrays, self.fit_info, meta_key="fit_info")

    @classmethod
    def load(cls, path: str | os.PathLike) -> StableDS:
        """Read a model written by :meth:`save`; verify its checksum and re-certify stability.

        Raises
        ------
        ModelFileError
            Unreadable, incomplete, corrupt or tampered file.
        StabilityError
            The stored parameters violate Eq. 10.
        """
        version = _peek_version(path)
        schema = _SCHEMAS.get(version, _SCHEMA)
        arrays, info, _ = read_guarded(path, FORMAT, tuple(_SCHEMAS), schema,
                                       meta_key="fit_info")
        sizes = {name: len(arrays[name]) for name in ("priors", "strength_priors", "target")
                 if name in arrays and arrays[name].ndim >= 1}
        limits = {"priors": MAX_FILE_COMPONENTS, "strength_priors": MAX_FILE_COMPONENTS,
                  "target": MAX_FILE_DIMS}
        for name, n in sizes.items():
            if n > limits[name]:
                raise ModelFileError(
                    f"{os.fspath(path)}: entry {name!r} declares {n} "
                    f"{'dimensions' if name == 'target' else 'components'}, more than the "
                    f"{limits[name]} a model file may hold (checked before the model is "
                    "built: each component costs about a millisecond)")
        strength = radius = None
        try:
            if "strength_priors" in arrays:
                log_range = arrays["strength_log_range"]
                if log_range.shape != (2,) or arrays["strength_radius"].shape != (1,):
                    raise ValueError("strength_log_range must have 2 entries and "
                                     "strength_radius 1")
                strength = StrengthFactor(arrays["strength_priors"], arrays["strength_means"],
                                          arrays["strength_covariances"], log_range)
                radius = float(arrays["strength_radius"][0])
            return cls(arrays["priors"], arrays["means"], arrays["covariances"],
                       arrays["target"], fit_info=info, status="loaded",
                       lyapunov=arrays.get("lyapunov"), strength=strength,
                       strength_radius=radius)
        except StabilityError:
            raise
        except (ValueError, np.linalg.LinAlgError) as exc:
            raise ModelFileError(f"{os.fspath(path)}: inconsistent model arrays ({exc})") from None

    def __repr__(self) -> str:
        st = self.fit_info.get("status", "-")
        extra = "" if self.strength is None else ", strength factor"
        return (f"StableDS(n_components={self.n_components}, n_dims={self.n_dims}, "
                f"status={st!r}{extra})")


def _check_strength(strength, radius, d: int) -> tuple[StrengthFactor | None, float | None]:
    """The strength factor and its taper radius, checked (ValueError saying what is wrong)."""
    if strength is None:
        if radius is not None:
            raise ValueError("strength_radius is given without a strength factor")
        return None, None
    if not isinstance(strength, StrengthFactor):
        raise TypeError(f"strength must be a StrengthFactor, got {type(strength).__name__}")
    if strength.n_dims != d:
        raise ValueError(f"the strength factor is over {strength.n_dims}-D positions, the model "
                         f"over {d}-D")
    K = len(strength.priors)
    if (strength.means.shape != (K, d + 1) or strength.covariances.shape != (K, d + 1, d + 1)
            or not all(np.all(np.isfinite(a)) for a in
                       (strength.priors, strength.means, strength.covariances))
            or np.any(strength.priors <= 0)
            or any(np.linalg.eigvalsh(0.5 * (S + S.T))[0] <= 0 for S in strength.covariances)):
        raise ValueError("the strength factor's GMM must have finite arrays of shapes (K,), "
                         f"(K, {d + 1}), (K, {d + 1}, {d + 1}), positive priors and positive "
                         "definite covariances")
    lo, hi = strength.log_range
    if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
        raise ValueError(f"the strength factor's log_range must be finite with lo <= hi, got "
                         f"{strength.log_range} (it keeps v within the demonstrated speeds)")
    if radius is None or not (np.isfinite(radius) and radius > 0):
        raise ValueError(f"strength_radius must be positive and finite, got {radius}")
    return strength, float(radius)


def _peek_version(path) -> int | None:
    """The file's ``version`` entry if it can be read (read_guarded reports every other fault)."""
    try:
        data = read_npz(path, f"{FORMAT} file", MAX_VALUES, member_bytes=RESERVED_BYTES,
                        only=("version",))
        return int(data["version"]) if "version" in data else None
    except FileNotFoundError:
        raise
    except Exception:  # noqa: BLE001 - read_guarded says what is wrong with the file
        return None

