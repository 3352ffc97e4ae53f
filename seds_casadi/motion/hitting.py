"""The hitting motion (paper Section 4): target field, strength factor and the steerable DS.

    xdot = f_h(x) = v(x) h(x)                                   (Eq. 3)
    h(x) = f(x) / ||f(x)||,   h(x*) = lim_{x -> x*} h(x)         (Eq. 8)
    v(x) = GMR of the speed on the position                      (Eq. 12)
    v* = v(x*),  psi* = h(x*)                                    (Eq. 13)
    xdot = kappa R_alpha v(R_alpha^T x) h(R_alpha^T x)           (Eq. 14)

Positions are relative to the ball (x* = 0), z up; R_alpha turns about +z through the ball.

Choices where the paper leaves them open (documented for users):

* **The limit at the target.** Near x* the SEDS model is linear, f(x) ~ J (x - x*) with
  J = sum_k h^k(x*) A_k, and every trajectory that is not exceptional arrives tangent to the
  eigenvector of J with the slowest (real) eigenvalue. psi* is that eigenvector, oriented along the
  demonstrations' arrival. A model whose slowest eigenvalues are a complex pair spirals into x*,
  has no limit direction, and is refused (ValueError).
* **Positivity of v (footnote 4).** The GMR is done on log-speed, v(x) = exp(E[log v | x]), which
  is positive everywhere by construction and equals Eq. 12 applied to log v.
* **How quickly swings line up (approach paths, on by default).** Plain SEDS fixes the limit
  direction psi* but not how fast swings line up with it: with the slowest and next eigenvalues
  of J close (ratio ~1.6 on the shipped demonstrations), the misalignment decays only as
  r^0.6 and a swing from the side still arrives degrees off (4 of 50 random starts more than
  1 deg off at the hit, all 50 commanded more than 1 deg off somewhere in the last centimetre;
  ``benchmarks/eval_hitting_accuracy.py --no-approach-paths``). :meth:`HittingMotion.fit`
  therefore adds *approach paths* to the SEDS data (not to the strength factor): short virtual
  paths over the last ``approach_length`` (10 cm) before the ball, b = c a^``approach_order``
  (a: distance behind the ball along the
  demonstrations' arrival direction u, b: sideways offset, 8 sides, two initial slopes), all
  tangent to u at the ball. They teach the direction objective (Eq. 9) to bring sideways
  motion in faster than the approach (order 3: the misalignment decays as r^2 in the ideal
  case). The fit is then checked from probe starts (the demonstrations' first points and
  random points in their box): if a swing misses or arrives more than ``max_direction_error``
  off, SEDS is refitted from the next random initialisation (``restarts``), and the best
  model is kept (a warning says so if none passes). ``approach_paths=False`` gives the paper's
  plain problem (Eq. 9-11).
* **Arrival constraint (an experimental extension, off by default).**
  ``HittingMotion.fit(..., approach_ratio=4)`` adds the constraint that the demonstrated arrival
  direction is an eigenvector of J whose rate is at least 4 times slower than any sideways
  motion (a condition on J at x* only; the approach paths above work on the flow around it).
* **The hitting velocity of a rollout.** Eq. 8 is singular at x*: a step that starts a fraction
  of a millimetre before the ball with a micrometre of sideways offset is commanded far off
  psi*, which no club (with inertia) would follow. A rollout therefore reports the club's mean
  velocity over the last control period before it reaches the ball (what a tracker at the
  controller's rate measures), and the commanded velocities stay in ``velocities``.
* **Resting mode.** After the hit, xdot = A_r (x - x_r) with A_r = -g I + w (z psi^T - psi z^T)
  (symmetric part -g I: stable) and the rest point x_r chosen so the velocity is continuous at the
  hit. w = 0 slows down along the hitting direction (flat fields); w = g curves the club upwards
  (fields where it could touch the ground).
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from ..core._io import atomic_npz
from ..core.demonstrations import Demonstrations
from ..core.errors import ConvergenceWarning, SEDSError, SolverError
from ..core.gmm import gmr_predict, responsibilities_sx
from ..core.seds import SEDS
from ..core.stable_ds import StableDS

__all__ = ["TargetField", "StrengthFactor", "HittingMotion", "RolloutResult", "rotation_z",
           "approach_paths"]

_TINY = 1e-200


def rotation_z(alpha: float) -> np.ndarray:
    """R_alpha: rotation by alpha [rad] about +z."""
    c, s = np.cos(alpha), np.sin(alpha)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _check_alpha_kappa(alpha, kappa) -> tuple[float, float]:
    try:
        alpha, kappa = float(alpha), float(kappa)
    except (TypeError, ValueError):
        raise TypeError(f"alpha and kappa must be numbers, got {alpha!r}, {kappa!r}") from None
    if not np.isfinite(alpha):
        raise ValueError(f"the hitting angle alpha must be finite (radians), got {alpha}")
    if not (np.isfinite(kappa) and kappa > 0):
        raise ValueError(f"the speed gain kappa must be positive and finite, got {kappa}")
    return alpha, kappa


def _points(X, d: int, name: str = "X") -> tuple[np.ndarray, bool]:
    X = np.asarray(X, dtype=float)
    single = X.ndim == 1
    X2 = np.atleast_2d(X)
    if X2.ndim != 2 or X2.shape[1] != d:
        raise ValueError(f"{name} must have shape (n, {d}) or ({d},), got {X.shape}")
    if not np.all(np.isfinite(X2)):
        raise ValueError(f"{name} contains NaN or infinite values")
    return X2, single


def approach_paths(direction, speed: float, length: float = 0.05, order: float = 3.0,
                   n_sides: int = 8, slopes: Sequence[float] = (0.3, 0.8), n_samples: int = 12
                   ) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Virtual paths into the ball along ``direction`` (see the module docstring).

    Each path is b = c a^order for a from ``length`` down to ``length / 30`` and then the ball,
    a the distance behind the ball along u = ``direction``, b the offset towards one of
    ``n_sides`` sides perpendicular to u, c set by the path's initial slope db/da (``slopes``).
    Velocities have magnitude ``speed`` and the path's tangent direction, u - order (b/a) w.

    Returns
    -------
    positions, velocities : lists of arrays, shape (n_samples + 1, 3), relative to the ball.
    """
    u = np.asarray(direction, dtype=float).ravel()
    if u.shape != (3,) or not np.all(np.isfinite(u)) or np.linalg.norm(u) == 0:
        raise ValueError(f"direction must be a finite non-zero 3-vector, got {direction!r}")
    u = u / np.linalg.norm(u)
    if not (length > 0 and order > 1 and speed > 0):
        raise ValueError(f"approach paths need length > 0, order > 1 and speed > 0, got "
                         f"{length}, {order}, {speed}")
    Q = np.linalg.svd(np.eye(3) - np.outer(u, u))[0][:, :2]
    a = np.geomspace(length, length / 30.0, int(n_samples))
    P, V = [], []
    for j in range(int(n_sides)):
        phi = 2.0 * np.pi * j / n_sides
        w = Q @ np.array([np.cos(phi), np.sin(phi)])
        for slope in slopes:
            b = slope * length / order * (a / length) ** order  # db/da = slope at a = length
            d = u[None, :] - (order * b / a)[:, None] * w[None, :]
            d /= np.linalg.norm(d, axis=1)[:, None]
            P.append(np.vstack([-a[:, None] * u + b[:, None] * w, np.zeros(3)]))
            V.append(speed * np.vstack([d, u]))
    return P, V


_approach_paths = approach_paths  # HittingMotion.fit's flag of the same name shadows it


def _probe_starts(demos: Demonstrations, n_random: int = 24) -> np.ndarray:
    """The demonstrations' first points and ``n_random`` fixed random points in their box."""
    first = np.array([p[0] for p in demos.positions])
    lo, hi = first.min(axis=0), first.max(axis=0)
    rng = np.random.default_rng(12345)
    return np.vstack([first, lo + (hi - lo) * rng.random((n_random, 3))])


class TargetField:
    """h(x) = f(x)/||f(x)|| (Eq. 8) of a certified StableDS, defined everywhere.

    A StableDS is certified globally asymptotically stable at x* (Eq. 10), so f vanishes nowhere
    else and h is well defined away from x*; at x* it takes its limit psi* (Eq. 13).

    Parameters
    ----------
    ds : StableDS
        Fitted with the direction objective (any objective works; Eq. 9 is the paper's).
    approach : array, shape (d,), optional
        A direction the demonstrations arrive along (orients psi*). Default: +x.

    Attributes
    ----------
    hitting_direction : array, shape (d,)
        psi* (Eq. 13), unit norm.
    jacobian : array, shape (d, d)
        J = df/dx at x*.
    """

    def __init__(self, ds: StableDS, approach=None) -> None:
        if not isinstance(ds, StableDS):
            raise TypeError(f"TargetField needs a StableDS, got {type(ds).__name__}")
        self.ds = ds
        d = ds.n_dims
        from ..core.gmm import responsibilities

        h = responsibilities(ds.target[None], ds.priors, ds.means[:, :d],
                             ds.covariances[:, :d, :d])[0]
        J = np.einsum("k,kij->ij", h, ds.A)
        ev, V = np.linalg.eig(J)
        i = int(np.argmax(ev.real))
        if abs(ev[i].imag) > 1e-9 * max(1.0, abs(ev[i].real)):
            raise ValueError(
                "the model spirals into its target (the slowest eigenvalues of df/dx at x* are a "
                f"complex pair, {ev[i]:.3g}), so the target field has no limit at x*; refit with "
                "more weight on the last samples (omega_upper) or another n_components")
        psi = np.real(V[:, i])
        psi /= np.linalg.norm(psi)
        a = np.eye(d)[0] if approach is None else np.asarray(approach, dtype=float)
        if np.dot(psi, a) < 0:
            psi = -psi
        self.approach = a
        self.jacobian = J
        self.hitting_direction = psi
        self.eigenvalues = ev

    def velocity(self, X) -> np.ndarray:
        """f(x) = sum_k h^k(x) A_k (x - x*): Eq. 5 for a certified model (Eq. 10a makes
        mu_xdot^k + A_k (x - mu_x^k) = A_k (x - x*)), in the form without cancellation near x*."""
        from ..core.gmm import responsibilities

        ds = self.ds
        d = ds.n_dims
        h = responsibilities(X, ds.priors, ds.means[:, :d], ds.covariances[:, :d, :d])
        return np.einsum("nk,kij,nj->ni", h, ds.A, X - ds.target)

    def __call__(self, X) -> np.ndarray:
        """h at points X, shape (n, d) or (d,), in the ds's coordinates; psi* at x* (Eq. 8)."""
        X2, single = _points(X, self.ds.n_dims)
        F = self.velocity(X2)
        nrm = np.linalg.norm(F, axis=1)
        out = np.where(nrm[:, None] > _TINY, F / np.maximum(nrm, _TINY)[:, None],
                       self.hitting_direction[None, :])
        return out[0] if single else out


class StrengthFactor:
    """v(x) > 0 by GMR on (position, log speed) (Eq. 12, in the log domain; footnote 4).

    GMR extrapolates linearly, so outside the demonstrated range of log-speeds [lo, hi] the
    prediction is saturated smoothly (C1, ``hi + log2 tanh((g - hi) / log2)`` above, likewise
    below): v stays between half the slowest and twice the fastest demonstrated speed, and is
    exactly the GMR of Eq. 12 (in log v) inside the range.

    Parameters
    ----------
    priors, means, covariances : the joint GMM over (x, log v), shapes (K,), (K, d+1),
        (K, d+1, d+1).
    log_range : (float, float)
        Demonstrated range of log v beyond which it saturates (infinite: no saturation).
    """

    def __init__(self, priors, means, covariances, log_range=(-np.inf, np.inf)) -> None:
        self.priors = np.asarray(priors, dtype=float)
        self.means = np.asarray(means, dtype=float)
        self.covariances = np.asarray(covariances, dtype=float)
        self.n_dims = self.means.shape[1] - 1
        self.log_range = (float(log_range[0]), float(log_range[1]))

    def _saturate(self, g, lib=np):
        """Identity on the demonstrated range [lo, hi] of log v; beyond it, a C1 tanh saturation
        that never goes more than log 2 past the range."""
        lo, hi = self.log_range
        if not (np.isfinite(lo) and np.isfinite(hi)):
            return g
        m = float(np.log(2.0))
        if lib is np:
            return np.where(g > hi, hi + m * np.tanh((g - hi) / m),
                            np.where(g < lo, lo + m * np.tanh((g - lo) / m), g))
        return ca.if_else(g > hi, hi + m * ca.tanh((g - hi) / m),
                          ca.if_else(g < lo, lo + m * ca.tanh((g - lo) / m), g))

    @classmethod
    def fit(cls, positions: np.ndarray, speeds: np.ndarray, n_components: int = 2,
            random_state=0) -> StrengthFactor:
        """Fit the joint GMM by k-means + EM.

        Parameters
        ----------
        positions : array, shape (n, d)
        speeds : array, shape (n,), all > 0
        """
        from sklearn.mixture import GaussianMixture

        speeds = np.asarray(speeds, dtype=float)
        if np.any(~np.isfinite(speeds)) or np.any(speeds <= 0):
            raise ValueError("speeds for the strength factor must be positive and finite")
        data = np.column_stack([positions, np.log(speeds)])
        gm = GaussianMixture(n_components=int(n_components), covariance_type="full",
                             reg_covar=1e-6, random_state=random_state).fit(data)
        return cls(gm.weights_, gm.means_, gm.covariances_,
                   log_range=(float(np.log(speeds.min())), float(np.log(speeds.max()))))

    def __call__(self, X) -> np.ndarray:
        """v at points X, shape (n, d) -> (n,), or (d,) -> float."""
        X2, single = _points(X, self.n_dims)
        d = self.n_dims
        logv = gmr_predict(X2, self.priors, self.means, self.covariances, np.arange(d), [d])
        v = np.exp(self._saturate(logv[:, 0]))
        return float(v[0]) if single else v


@dataclass
class RolloutResult:
    """A swing integrated by :meth:`HittingMotion.rollout`.

    Attributes
    ----------
    times : array, shape (T,)
    positions : array, shape (T, 3)
        Club-head positions in the field frame.
    velocities : array, shape (T, 3)
        Commanded velocities.
    balls : array, shape (T, 3)
        Ball position at each step.
    hit : bool
        Whether the club reached the ball (crossed the plane through it, perpendicular to the
        commanded direction, within ``hit_radius``).
    hit_time, hit_position, hit_velocity :
        At the moment of the hit (interpolated to the crossing of the plane through the ball
        perpendicular to the commanded hitting direction); the hitting velocity is the club's
        mean velocity over the last control period ``dt``. None without a hit.
    commanded_direction : array, shape (3,)
        R_alpha psi* for the alpha in force at the hit.
    commanded_speed : float
        kappa v* at the hit.
    """

    times: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    balls: np.ndarray
    hit: bool
    hit_time: float | None = None
    hit_position: np.ndarray | None = None
    hit_velocity: np.ndarray | None = None
    commanded_direction: np.ndarray | None = None
    commanded_speed: float | None = None
    events: list = field(default_factory=list)

    @property
    def direction_error_deg(self) -> float:
        """Angle [deg] between the hitting velocity and the commanded direction."""
        if not self.hit:
            return float("nan")
        u = self.hit_velocity / np.linalg.norm(self.hit_velocity)
        return float(np.degrees(np.arccos(np.clip(u @ self.commanded_direction, -1, 1))))

    @property
    def speed_error(self) -> float:
        """Relative error of the hitting speed against kappa v*."""
        if not self.hit:
            return float("nan")
        return float(np.linalg.norm(self.hit_velocity) / self.commanded_speed - 1.0)


class HittingMotion:
    """The steerable hitting DS of Eq. 14, from a target field and a strength factor.

    Parameters
    ----------
    target_field : TargetField
    strength : StrengthFactor
    rest_length : float
        Distance [m] over which the resting mode stops the club after the hit.
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
        """Learn the target field (SEDS, direction objective) and the strength factor (GMR).

        Parameters
        ----------
        demos : Demonstrations
            3-D club-head demonstrations ending at the ball, which must be the origin
            (``target=[0, 0, 0]``), with a non-zero speed there.
        n_components : int
            Gaussians of the SEDS model (the paper used 3).
        strength_components : int
            Gaussians of the strength factor (the paper used 2).
        random_state : int
            Seed of the first SEDS initialisation (k-means + EM); restarts use the next seeds.
        approach_ratio : float or None, default None
            If given, constrain the SEDS model so that the demonstrations' mean arrival direction
            is its slowest way into the ball, with sideways motion at least this many times faster
            (see :func:`seds_casadi.kernels.approach_constraints`). Experimental; None (default)
            leaves it out.
        approach_paths : bool, default True
            Add virtual approach paths near the ball to the SEDS data so that swings line up with
            psi* before they reach it (see the module docstring); False: the paper's data only.
        approach_length, approach_order : float
            Length [m] of the approach paths and the order of their contact with the arrival line.
        restarts : int, default 3
            Initialisations tried at most when the probe check fails (1: no restart).
        max_direction_error : float, default 1.0
            Probe check threshold [deg]: every probe swing must hit with its direction within it.
        **seds_kwargs
            Passed to :class:`SEDS` (e.g. ``omega_upper``).

        Notes
        -----
        ``motion.fit_info`` records the tries: seed, probe errors, and which model was kept.
        """
        if not isinstance(demos, Demonstrations):
            raise TypeError(f"fit expects Demonstrations, got {type(demos).__name__}")
        if demos.n_dims != 3:
            raise ValueError(f"hitting demonstrations must be 3-D, got {demos.n_dims}-D")
        if np.linalg.norm(demos.target) > 1e-12:
            raise ValueError("give the demonstrations relative to the ball with target=[0, 0, 0]")
        if isinstance(restarts, bool) or int(restarts) != restarts or restarts < 1:
            raise ValueError(f"restarts must be a positive integer, got {restarts!r}")
        if not (np.isfinite(max_direction_error) and max_direction_error > 0):
            raise ValueError(f"max_direction_error must be positive, got {max_direction_error}")
        end_speed = np.mean([np.linalg.norm(v[-1]) for v in demos.velocities])
        top = max(np.linalg.norm(v, axis=1).max() for v in demos.velocities)
        if end_speed <= 0.05 * top:
            raise ValueError(
                "the demonstrations' speed at the target is (nearly) zero: they stop at the ball "
                "instead of hitting it, so there is no hitting motion to learn")
        seds_kwargs.setdefault("objective", "direction")
        approach = np.mean([v[-1] / np.linalg.norm(v[-1]) for v in demos.velocities], axis=0)
        approach /= np.linalg.norm(approach)
        if approach_ratio is not None:
            seds_kwargs.setdefault("approach_direction", approach)
            seds_kwargs.setdefault("approach_ratio", approach_ratio)
        data = demos
        if approach_paths:
            P, V = _approach_paths(approach, float(end_speed), approach_length, approach_order)
            data = Demonstrations(list(demos.positions) + P,
                                  velocities=list(demos.velocities) + V, target=np.zeros(3))
        X = np.concatenate(demos.positions)
        S = np.concatenate([np.linalg.norm(v, axis=1) for v in demos.velocities])
        keep = S > 1e-3 * S.max()
        strength = StrengthFactor.fit(X[keep], S[keep], strength_components, random_state)
        starts = _probe_starts(demos)
        seed0 = 0 if random_state is None else int(random_state)
        tries, best = [], None
        for i in range(int(restarts)):
            seed = seed0 + i
            try:
                ds = SEDS(n_components, random_state=seed, **seds_kwargs).fit(data).model_
                motion = cls(TargetField(ds, approach=approach), strength)
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
            if worst <= max_direction_error:
                break
        if best is None:
            raise SolverError(f"no SEDS fit succeeded in {restarts} tries: "
                              + "; ".join(t["error"] for t in tries), "failed")
        worst, motion, kept = best
        if worst > max_direction_error:
            warnings.warn(
                f"after {len(tries)} SEDS fits the best hitting motion still arrives up to "
                f"{worst:.2f} deg off psi* from a probe start (asked: {max_direction_error} deg); "
                "try more restarts, another n_components, or approach_paths=True",
                ConvergenceWarning, stacklevel=2)
        motion.fit_info = {"tries": tries, "kept": kept, "approach_paths": bool(approach_paths),
                           "probe_starts": len(starts)}
        return motion

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
        alpha, kappa = _check_alpha_kappa(alpha, kappa)
        X, _ = _points(starts, 3, "starts")
        n = len(X)
        psi = rotation_z(alpha) @ self.hitting_direction
        x, prev = X.copy(), X.copy()
        hit = np.zeros(n, bool)
        vel = np.full((n, 3), np.nan)
        active = np.ones(n, bool)
        for step in range(int(np.ceil(max_time / dt))):
            idx = np.flatnonzero(active)
            if idx.size == 0:
                break
            xa = x[idx]
            v = self.velocity(xa, alpha, kappa)
            xn = xa + dt * v
            s0, s1 = xa @ psi, xn @ psi
            cross = (s0 < 0) & (s1 >= 0)
            lam = np.where(cross, -s0 / np.where(cross, s1 - s0, 1.0), 0.0)
            ph = xa + lam[:, None] * (xn - xa)
            done = cross & (np.linalg.norm(ph, axis=1) <= hit_radius)
            if np.any(done):
                j = idx[done]
                back = prev[j] + lam[done, None] * (xa[done] - prev[j]) if step else xa[done]
                chord = (ph[done] - back) / dt if step else v[done]
                vel[j] = chord
                hit[j] = True
                active[j] = False
            prev[idx] = xa
            x[idx] = xn
        spd = np.linalg.norm(vel, axis=1)
        cosang = np.clip((vel @ psi) / np.where(hit, spd, 1.0), -1.0, 1.0)
        err = np.where(hit, np.degrees(np.arccos(cosang)), np.nan)
        serr = np.where(hit, spd / (kappa * self.hitting_speed) - 1.0, np.nan)
        return hit, err, serr

    # ------------------------------------------------------------ persistence
    def save(self, folder: str | os.PathLike) -> None:
        """Write the motion into ``folder``: ``stable_ds.npz`` (the certified SEDS model, with
        its checksum) and ``strength.npz`` (strength factor, approach direction, rest length);
        no pickle."""
        folder = os.fspath(folder)
        os.makedirs(folder, exist_ok=True)
        self.target_field.ds.save(os.path.join(folder, "stable_ds.npz"))
        s = self.strength
        atomic_npz(os.path.join(folder, "strength.npz"), priors=s.priors, means=s.means,
                   covariances=s.covariances, log_range=np.array(s.log_range),
                   approach=np.asarray(self.target_field.approach, float),
                   rest_length=np.array(self.rest_length))

    @classmethod
    def load(cls, folder: str | os.PathLike) -> HittingMotion:
        """Read a motion written by :meth:`save` (the SEDS model is re-certified)."""
        folder = os.fspath(folder)
        ds = StableDS.load(os.path.join(folder, "stable_ds.npz"))
        path = os.path.join(folder, "strength.npz")
        try:
            with np.load(path, allow_pickle=False) as f:
                strength = StrengthFactor(f["priors"], f["means"], f["covariances"],
                                          tuple(f["log_range"]))
                approach = f["approach"]
                rest = float(f["rest_length"])
        except (OSError, KeyError, ValueError) as exc:
            raise ValueError(f"{path}: not a strength-factor file ({exc})") from None
        return cls(TargetField(ds, approach=approach if approach.size == 3 else None),
                   strength, rest)

    # ------------------------------------------------------------ evaluation
    def velocity(self, X, alpha: float = 0.0, kappa: float = 1.0) -> np.ndarray:
        """Eq. 14: kappa R_alpha v(R_alpha^T x) h(R_alpha^T x), x relative to the ball.

        Parameters
        ----------
        X : array, shape (n, 3) or (3,)
        alpha : float
            Hitting angle [rad] about +z.
        kappa : float
            Speed gain (> 0).
        """
        alpha, kappa = _check_alpha_kappa(alpha, kappa)
        X2, single = _points(X, 3)
        R = rotation_z(alpha)
        Y = X2 @ R  # rows: R^T x
        out = kappa * (self.strength(Y)[:, None] * self.target_field(Y)) @ R.T
        return out[0] if single else out

    def hitting_velocity(self, alpha: float = 0.0, kappa: float = 1.0) -> np.ndarray:
        """The commanded velocity at the ball, kappa v* R_alpha psi*."""
        alpha, kappa = _check_alpha_kappa(alpha, kappa)
        return kappa * self.hitting_speed * rotation_z(alpha) @ self.hitting_direction

    def resting_velocity(self, X, hit_position, hit_velocity, mode: str = "flat") -> np.ndarray:
        """The resting-mode DS after the hit (see module docstring).

        Parameters
        ----------
        X : array, shape (n, 3) or (3,)
        hit_position, hit_velocity : array, shape (3,)
        mode : {"flat", "arc"}
        """
        X2, single = _points(X, 3)
        A, rest = self._rest_system(np.asarray(hit_position, float),
                                    np.asarray(hit_velocity, float), mode)
        out = (X2 - rest) @ A.T
        return out[0] if single else out

    def _rest_system(self, p_hit, v_hit, mode):
        if mode not in ("flat", "arc"):
            raise ValueError(f"unknown resting mode {mode!r}; valid: flat, arc")
        speed = float(np.linalg.norm(v_hit))
        if speed <= 0:
            return -np.eye(3), p_hit.copy()
        psi = v_hit / speed
        g = speed / self.rest_length
        z = np.array([0.0, 0.0, 1.0])
        w = g if mode == "arc" else 0.0
        A = -g * np.eye(3) + w * (np.outer(z, psi) - np.outer(psi, z))
        rest = p_hit + np.linalg.solve(A, -v_hit)  # A (p_hit - rest) = v_hit
        return A, rest

    # ------------------------------------------------------------ integration
    def rollout(self, start, alpha: float = 0.0, kappa: float = 1.0, dt: float = 0.002,
                ball=None, perturb: Sequence[dict] | None = None, max_time: float = 5.0,
                rest_mode: str = "flat", rest_time: float = 0.5,
                params: Callable | None = None, hit_radius: float = 0.02) -> RolloutResult:
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
            and any of ``ball`` (new position), ``alpha``, ``kappa``.
        max_time : float
            Give up (no hit) after this time.
        rest_mode : {"flat", "arc"}
        rest_time : float
            How long to integrate the resting mode after the hit.
        params : callable, optional
            ``params(t, ball) -> (alpha, kappa)`` evaluated every step (e.g. a hitting-parameter
            model reacting to a moving hole); overrides alpha and kappa.
        hit_radius : float
            The club hits the ball when it crosses the plane through the ball perpendicular to
            the commanded hitting direction within this distance [m] of the ball's centre.
        """
        x, _ = _points(start, 3, "start")
        x = x[0].copy()
        alpha, kappa = _check_alpha_kappa(alpha, kappa)
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be positive, got {dt}")
        b = np.zeros(3) if ball is None else _points(ball, 3, "ball")[0][0].copy()
        events = sorted(perturb or [], key=lambda e: float(e["t"]))
        for e in events:
            if "t" not in e or not np.isfinite(float(e["t"])):
                raise ValueError(f"each perturbation needs a finite time 't': {e!r}")
        if rest_mode not in ("flat", "arc"):
            raise ValueError(f"unknown resting mode {rest_mode!r}; valid: flat, arc")
        if not (np.isfinite(hit_radius) and hit_radius > 0):
            raise ValueError(f"hit_radius must be positive, got {hit_radius}")
        t = 0.0
        T, P, V, B = [], [], [], []
        applied = []
        ei = 0
        hit = None
        n_max = int(np.ceil(max_time / dt))
        for _ in range(n_max):
            while ei < len(events) and float(events[ei]["t"]) <= t + 1e-12:
                e = events[ei]
                if "ball" in e:
                    b = _points(e["ball"], 3, "perturbation ball")[0][0].copy()
                if "alpha" in e or "kappa" in e:
                    alpha, kappa = _check_alpha_kappa(e.get("alpha", alpha), e.get("kappa", kappa))
                applied.append(dict(e))
                ei += 1
            if params is not None:
                alpha, kappa = _check_alpha_kappa(*params(t, b.copy()))
            v = self.velocity(x - b, alpha, kappa)
            T.append(t)
            P.append(x.copy())
            V.append(v)
            B.append(b.copy())
            psi = rotation_z(alpha) @ self.hitting_direction
            x_new = x + dt * v
            s0 = float(psi @ (x - b))
            s1 = float(psi @ (x_new - b))
            if s0 < 0 <= s1 and np.linalg.norm(
                    (x + (-s0 / (s1 - s0)) * (x_new - x)) - b) <= hit_radius:
                lam = -s0 / (s1 - s0)
                p_hit = x + lam * (x_new - x)
                # the hitting velocity is the club's mean velocity over the last control period
                # (Eq. 8 is singular at the ball: the command of a step that starts a hair
                # before it can point anywhere; see the module docstring)
                v_hit = v.copy()
                if len(P) >= 2:
                    v_hit = (p_hit - (P[-2] + lam * (P[-1] - P[-2]))) / dt
                hit = (t + lam * dt, p_hit, v_hit, psi, kappa * self.hitting_speed)
                x, t = p_hit, t + lam * dt
                break
            x, t = x_new, t + dt
        if hit is None:
            return RolloutResult(np.array(T), np.array(P), np.array(V), np.array(B), False,
                                 events=applied)
        t_hit, p_hit, v_hit, psi, spd = hit
        A, rest = self._rest_system(p_hit, v_hit, rest_mode)
        for _ in range(int(np.ceil(rest_time / dt)) + 1):
            v = (x - rest) @ A.T
            T.append(t)
            P.append(x.copy())
            V.append(v)
            B.append(b.copy())
            x, t = x + dt * v, t + dt
        return RolloutResult(np.array(T), np.array(P), np.array(V), np.array(B), True, t_hit,
                             p_hit, v_hit, psi, spd, events=applied)

    # ------------------------------------------------------------ CasADi
    def compiled(self):
        """Eq. 14 compiled to C and called through fixed buffers, for a real-time loop.

        Returns a callable ``(x, alpha, kappa) -> xdot`` (x of shape (3,), relative to the ball),
        about 2 us per call here against about 450 us for :meth:`velocity`; it falls back to
        CasADi's virtual machine without a C compiler. Not thread-safe.
        """
        from ..codegen import FastEvaluator, compile_functions

        return FastEvaluator(compile_functions([self.to_casadi()])[0])

    def to_casadi(self, name: str = "hitting_ds") -> ca.Function:
        """Eq. 14 as a CasADi Function (x (3,), alpha, kappa) -> xdot (3,), for code generation.

        Near the ball (||f|| below 1e-200) the target field takes its limit psi*, as in numpy.
        """
        x = ca.SX.sym("x", 3)
        alpha = ca.SX.sym("alpha")
        kappa = ca.SX.sym("kappa")
        c, s = ca.cos(alpha), ca.sin(alpha)
        R = ca.vertcat(ca.horzcat(c, -s, 0), ca.horzcat(s, c, 0), ca.horzcat(0, 0, 1))
        y = R.T @ x
        ds = self.target_field.ds
        hw = responsibilities_sx(y, ds.priors, ds.means[:, :3], ds.covariances[:, :3, :3])
        f = ca.SX.zeros(3, 1)
        for k in range(ds.n_components):
            f = f + hw[k] * (ca.DM(ds.A[k]) @ (y - ca.DM(ds.target)))
        nf = ca.norm_2(f)
        psi = ca.DM(self.hitting_direction)
        h = ca.if_else(nf > _TINY, f / ca.fmax(nf, _TINY), psi)
        sf = self.strength
        d = 3
        hs = responsibilities_sx(y, sf.priors, sf.means[:, :d], sf.covariances[:, :d, :d])
        logv = 0
        for k in range(len(sf.priors)):
            gain = np.linalg.solve(sf.covariances[k, :d, :d], sf.covariances[k, :d, d])
            logv = logv + hs[k] * (sf.means[k, d] + ca.dot(ca.DM(gain), y - ca.DM(sf.means[k, :d])))
        xdot = kappa * (R @ (ca.exp(sf._saturate(logv, lib=ca)) * h))
        return ca.Function(name, [x, alpha, kappa], [xdot], ["x", "alpha", "kappa"], ["xdot"])

