"""SEDS: learn a globally stable GMM dynamical system, built in CasADi and solved by IPOPT.

The problem (paper Section 4.1, Eq. 4-11; original objectives of Khansari-Zadeh and Billard 2011)

    min_theta J(theta)   subject to Eq. 10 (a)-(e)

is written symbolically in CasADi (SX) with the constraints satisfied by construction (see
:mod:`seds_casadi.parametrization`) and solved by IPOPT with exact gradients and exact Hessians
from algorithmic differentiation. After every solve the model is certified numerically
(:func:`seds_casadi.stable_ds.certify`); a model that fails is never returned.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field

import casadi as ca
import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin

from .demonstrations import Demonstrations
from .errors import ConvergenceWarning, SolverError
from .gmm import responsibilities
from .objectives import SumKernels, approach_constraints
from .parametrization import OBJECTIVES, Layout, unpack_numpy
from .stable_ds import StableDS

__all__ = ["SEDS", "SEDSProblem", "direction_weights"]

_OK_STATUS = ("Solve_Succeeded", "Solved_To_Acceptable_Level")
_HESSIANS = ("exact", "limited-memory")


def direction_weights(phase: np.ndarray, omega_lower: float, omega_upper: float) -> np.ndarray:
    """Per-sample weights of Eq. 11: w = (t / T^n)(omega_u - omega_l) + omega_l.

    Parameters
    ----------
    phase : array, shape (n,)
        t / T^n of each sample within its demonstration, in [0, 1].
    omega_lower, omega_upper : float
        Weights of the first and last sample of each demonstration (both > 0).
    """
    return np.asarray(phase) * (omega_upper - omega_lower) + omega_lower


# ------------------------------------------------------------------ the problem
@dataclass
class SEDSProblem:
    """The SEDS problem for one data set, built and ready to solve (or to inspect).

    Attributes
    ----------
    layout : Layout
        Index map of the optimisation vector.
    objective : str
    X, Xd : array, shape (n, d)
        Scaled data in the attractor frame (x* at the origin).
    weights : array, shape (n,)
    position_scale, velocity_scale : float
        sx and sv: caller units = scaled units times these.
    target : array, shape (d,)
    theta0 : array, shape (layout.size,)
        Initial guess from k-means + EM.
    lbx, ubx : array
        Simple bounds on theta (keep exp-parametrised factors in a sane range).
    margin : float
        Stability margin of the parametrization (scaled units).
    kernels : SumKernels
        J, its exact gradient and Hessian (mapped per-sample CasADi kernels).
    objective_function : casadi.Function
        theta -> J(theta).
    """

    layout: Layout
    objective: str
    X: np.ndarray
    Xd: np.ndarray
    weights: np.ndarray
    position_scale: float
    velocity_scale: float
    target: np.ndarray
    theta0: np.ndarray
    lbx: np.ndarray
    ubx: np.ndarray
    margin: float
    kernels: SumKernels = field(repr=False)
    objective_function: ca.Function = field(repr=False)

    def speed_factor(self, theta: np.ndarray) -> float:
        """Least-squares speed calibration c* = sum_i f_i . xdot_i / sum_i ||f_i||^2 (> 0).

        The direction objective (Eq. 9) fixes f only up to a positive factor (scaling every A_k by
        c > 0 changes neither the directions nor the stability). For the direction objective the
        returned model is scaled by c*, the factor that best matches the demonstrated speeds, so
        its reproductions and velocity errors are meaningful; h = f/||f|| (Eq. 8) is unchanged.
        Returns 1 if the fit is so poor that c* would not be positive.
        """
        p = unpack_numpy(np.asarray(theta, dtype=float), self.layout, self.margin)
        h = responsibilities(self.X, p["priors"], p["mu"], p["Sx"])
        return _speed_factor(p["A"], h, self.X, self.Xd)

    def to_model_arrays(self, theta: np.ndarray, speed_factor: float | None = None
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Priors, means and joint covariances in the caller's coordinates for a given theta.

        Sigma_xdot = A Sigma_x A^T + Q with Q the optimised noise (likelihood) or the
        responsibility-weighted residual covariance of the data (other objectives). For the
        direction objective the A_k are scaled by :meth:`speed_factor` first (pass it as
        ``speed_factor`` if already computed).
        """
        p = unpack_numpy(np.asarray(theta, dtype=float), self.layout, self.margin)
        K, d = self.layout.K, self.layout.d
        sx, sv = self.position_scale, self.velocity_scale
        if "Q" in p:
            Q = p["Q"]
        else:
            h = responsibilities(self.X, p["priors"], p["mu"], p["Sx"])
            if self.objective == "direction":
                c = speed_factor if speed_factor is not None else _speed_factor(
                    p["A"], h, self.X, self.Xd)
                p["A"] = p["A"] * c
            Q = np.empty((K, d, d))
            for k in range(K):
                r = self.Xd - self.X @ p["A"][k].T
                wk = h[:, k] / max(h[:, k].sum(), 1e-300)
                Q[k] = (r * wk[:, None]).T @ r + 1e-6 * np.eye(d)
        means = np.empty((K, 2 * d))
        covs = np.empty((K, 2 * d, 2 * d))
        for k in range(K):
            A = p["A"][k] * (sv / sx)
            Sx = p["Sx"][k] * sx**2
            mx = p["mu"][k] * sx
            means[k, :d] = mx + self.target
            means[k, d:] = A @ mx
            covs[k, :d, :d] = Sx
            covs[k, d:, :d] = A @ Sx
            covs[k, :d, d:] = (A @ Sx).T
            covs[k, d:, d:] = A @ Sx @ A.T + Q[k] * sv**2
            covs[k] = 0.5 * (covs[k] + covs[k].T)
        return p["priors"].copy(), means, covs


def _speed_factor(A, h, X, Xd) -> float:
    F = np.einsum("nk,kij,nj->ni", h, A, X)
    num, den = float(np.sum(F * Xd)), float(np.sum(F * F))
    return num / den if (num > 0 and den > 0) else 1.0


def _initial_theta(
    layout: Layout, X: np.ndarray, Xd: np.ndarray, margin: float, random_state
) -> np.ndarray:
    """k-means + EM on the joint (x, xdot) data, then projected onto the stable set.

    The GMR gain A_k = Sigma_xdotx Sigma_x^-1 of each EM component is split into symmetric and
    skew parts; the symmetric part's eigenvalues are clipped to at most -max(5 % of its largest
    magnitude, 2 m), which gives the nearest stable A_k in that sense.
    """
    from sklearn.mixture import GaussianMixture

    K, d = layout.K, layout.d
    gm = GaussianMixture(
        n_components=K, covariance_type="full", init_params="kmeans", reg_covar=1e-6,
        random_state=random_state, max_iter=200,
    ).fit(np.hstack([X, Xd]))
    theta = np.zeros(layout.size)
    logits = np.log(np.maximum(gm.weights_, 1e-12))
    theta[: layout.n_logits] = logits[:-1] - logits[-1]
    for k in range(K):
        s = layout.slices(k)
        mu = gm.means_[k, :d]
        S = gm.covariances_[k]
        Sx = S[:d, :d] + 1e-6 * np.eye(d)
        theta[s["mu"]] = mu
        theta[s["L"]] = layout.pack_tril(np.linalg.cholesky(Sx))
        A = np.linalg.solve(Sx, S[:d, d:]).T  # Sigma_xdotx Sigma_x^-1
        sym = 0.5 * (A + A.T)
        ev, V = np.linalg.eigh(sym)
        cap = -max(0.05 * np.max(np.abs(ev)), 2.0 * margin, 1e-3)
        ev = np.minimum(ev, cap)
        P = V @ np.diag(-ev - margin) @ V.T  # = B B^T
        theta[s["B"]] = layout.pack_tril(np.linalg.cholesky(0.5 * (P + P.T)))
        skew = 0.5 * (A - A.T)
        theta[s["W"]] = [skew[i, j] for i, j in layout.strict]
        if layout.with_noise:
            As = V @ np.diag(ev) @ V.T + skew
            r = Xd - X @ As.T
            wk = gm.predict_proba(np.hstack([X, Xd]))[:, k]
            Q = (r * (wk / max(wk.sum(), 1e-300))[:, None]).T @ r + 1e-4 * np.eye(d)
            theta[s["Q"]] = layout.pack_tril(np.linalg.cholesky(Q))
    return theta


# ------------------------------------------------------------------ the learner
class SEDS(RegressorMixin, BaseEstimator):
    """Stable Estimator of Dynamical Systems, in CasADi + IPOPT.

    Parameters
    ----------
    n_components : int
        Number K of Gaussians.
    objective : {"direction", "mse", "likelihood"}, default "direction"
        ``"direction"``: the paper's Eq. 9 (weighted cosine between demonstrated and model
        velocities, weights of Eq. 11); ``"mse"`` and ``"likelihood"``: the original SEDS objectives
        (mean squared velocity error; negative log-likelihood of the joint GMM).
    random_state : int, numpy Generator or None
        Seed of the k-means + EM initialisation (the fit is deterministic for a given seed).
    omega_lower, omega_upper : float, default 1.0 and 2.0
        Eq. 11 weights of each demonstration's first and last sample (direction objective). The
        paper gives no values; our default doubles the weight at the end, where the paper says
        accuracy matters most.
    stability_margin : float, default 1e-3
        m in A_k + A_k^T <= -2 m I, in the scaled frame (unit-RMS positions and velocities).
    max_iter : int, default 1000
        IPOPT iteration limit (SEDS's default).
    tol : float, default 1e-6
        IPOPT's convergence tolerance.
    tol_objective_change : float, default 1e-5
        Stop (status ``Solved_To_Acceptable_Level``) once the relative change of the objective has
        stayed below this for 5 iterations with a dual infeasibility below 1e-2, like SEDS's
        ``tol_stopping``. The direction objective has long flat valleys where IPOPT otherwise
        spends hundreds of iterations for gains below 1e-5. Use 0 to disable.
    hessian : {"exact", "limited-memory"}, default "exact"
        Exact Hessians by algorithmic differentiation, or IPOPT's L-BFGS approximation.
    require_convergence : bool, default False
        If True, an IPOPT run that stops without converging raises :class:`SolverError`; if False
        it gives a :class:`ConvergenceWarning` and returns the (certified) model, with the status in
        ``fit_info``.
    compile : bool, default True
        Compile the per-sample kernels to C when a C compiler is found (cached on disk; see
        :mod:`seds_casadi.kernels`); otherwise CasADi's virtual machine evaluates them.
    approach_direction : array, shape (d,), optional
        If given, constrain the model so that this direction is the slowest way into the target,
        with motion across it at least ``approach_ratio`` times faster (an extension of the paper
        for hitting motions; see :func:`seds_casadi.kernels.approach_constraints`).
    approach_ratio : float, default 4.0
    verbose : bool, default False
        Print IPOPT's iteration log.
    """

    def __init__(
        self,
        n_components: int = 5,
        objective: str = "direction",
        random_state=None,
        omega_lower: float = 1.0,
        omega_upper: float = 2.0,
        stability_margin: float = 1e-3,
        max_iter: int = 1000,
        tol: float = 1e-6,
        tol_objective_change: float = 1e-5,
        hessian: str = "exact",
        require_convergence: bool = False,
        compile: bool = True,
        approach_direction=None,
        approach_ratio: float = 4.0,
        verbose: bool = False,
    ) -> None:
        # scikit-learn convention: store the parameters as given; fit() validates them
        self.n_components = n_components
        self.objective = objective
        self.random_state = random_state
        self.omega_lower = omega_lower
        self.omega_upper = omega_upper
        self.stability_margin = stability_margin
        self.max_iter = max_iter
        self.tol = tol
        self.tol_objective_change = tol_objective_change
        self.hessian = hessian
        self.require_convergence = require_convergence
        self.compile = compile
        self.approach_direction = approach_direction
        self.approach_ratio = approach_ratio
        self.verbose = verbose

    def _validated(self) -> dict:
        """The parameters checked and normalised (raises ValueError/TypeError with a remedy)."""
        K = self.n_components
        if isinstance(K, bool) or not isinstance(K, (int, np.integer)):
            raise TypeError(f"n_components must be an integer, got {K!r}")
        if K < 1:
            raise ValueError(f"n_components must be at least 1, got {K}")
        if self.objective not in OBJECTIVES:
            raise ValueError(f"unknown objective {self.objective!r}; valid: {', '.join(OBJECTIVES)}")
        if self.hessian not in _HESSIANS:
            raise ValueError(f"unknown hessian {self.hessian!r}; valid: {', '.join(_HESSIANS)}")
        for name in ("omega_lower", "omega_upper"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be a positive finite weight, got {v}")
        if not (np.isfinite(self.stability_margin) and self.stability_margin > 0):
            raise ValueError(f"stability_margin must be positive, got {self.stability_margin}")
        if int(self.max_iter) < 1:
            raise ValueError(f"max_iter must be at least 1, got {self.max_iter}")
        if not (np.isfinite(self.tol) and self.tol > 0):
            raise ValueError(f"tol must be positive, got {self.tol}")
        toc = self.tol_objective_change
        if not (np.isfinite(toc) and toc >= 0):
            raise ValueError(f"tol_objective_change must be >= 0, got {toc}")
        u = self.approach_direction
        if u is not None:
            u = np.asarray(u, dtype=float).ravel()
            if not (np.all(np.isfinite(u)) and np.linalg.norm(u) > 0):
                raise ValueError("approach_direction must be a finite non-zero vector")
            u = u / np.linalg.norm(u)
        if not (np.isfinite(self.approach_ratio) and self.approach_ratio >= 1):
            raise ValueError(f"approach_ratio must be >= 1, got {self.approach_ratio}")
        return {"n_components": int(K), "max_iter": int(self.max_iter),
                "tol_objective_change": float(toc) if toc else 1e20, "approach_direction": u}

    def build_problem(self, demos: Demonstrations) -> SEDSProblem:
        """Scale the data, initialise by k-means + EM and build the CasADi problem."""
        self._validated()
        if not isinstance(demos, Demonstrations):
            raise TypeError(
                f"fit expects a seds_casadi.Demonstrations, got {type(demos).__name__}; "
                "wrap your arrays with Demonstrations(positions, dt=...)"
            )
        X, Xd, phase, _ = demos.stacked()
        d = X.shape[1]
        layout = Layout(int(self.n_components), d, with_noise=self.objective == "likelihood")
        # each sample gives d velocity equations; ask for at least one per parameter
        if X.shape[0] * d < layout.size or X.shape[0] < 2 * self.n_components:
            raise ValueError(
                f"{X.shape[0]} samples are too few for n_components={self.n_components} in "
                f"{d}-D ({layout.size} parameters, {X.shape[0] * d} velocity values); use fewer "
                "components or more samples"
            )
        sx = float(np.sqrt(np.mean(np.sum(X**2, axis=1)) / d))
        sv = float(np.sqrt(np.mean(np.sum(Xd**2, axis=1)) / d))
        if not (sx > 0 and sv > 0):
            raise ValueError("the demonstrations do not move away from the target; nothing to learn")
        Xs, Xds = X / sx, Xd / sv
        if self.objective == "direction":
            w = direction_weights(phase, self.omega_lower, self.omega_upper)
        else:
            w = np.ones(len(X))
        theta0 = _initial_theta(layout, Xs, Xds, self.stability_margin, self.random_state)
        lbx = np.full(layout.size, -np.inf)
        ubx = np.full(layout.size, np.inf)
        diag_pos = [i for i, (a, b) in enumerate(layout.tril) if a == b]
        for k in range(layout.K):
            s = layout.slices(k)
            lbx[s["mu"]], ubx[s["mu"]] = -50.0, 50.0
            for name in ("L", "B", "Q"):
                if name in s:
                    idx = np.arange(s[name].start, s[name].stop)[diag_pos]
                    lbx[idx], ubx[idx] = np.log(1e-3), np.log(1e2)
        theta0 = np.clip(theta0, lbx + 1e-9, ubx - 1e-9)
        speed = np.linalg.norm(Xds, axis=1)
        if self.objective == "direction":
            moving = speed > 0
            coef = np.where(moving, w / np.where(moving, speed, 1.0), 0.0)
            norm = float(np.sum(w))
        else:
            coef = np.ones(len(Xs))
            norm = float(len(Xs))
        kernels = SumKernels(layout, self.objective, self.stability_margin, Xs, Xds, coef, norm,
                             compile=self.compile)
        return SEDSProblem(
            layout=layout, objective=self.objective, X=Xs, Xd=Xds, weights=w,
            position_scale=sx, velocity_scale=sv, target=demos.target.copy(), theta0=theta0,
            lbx=lbx, ubx=ubx, margin=self.stability_margin, kernels=kernels,
            objective_function=kernels.casadi_function(),
        )

    def fit(self, X, y=None, target=None) -> SEDS:
        """Learn a certified globally stable DS from demonstrations.

        Parameters
        ----------
        X : Demonstrations or array, shape (n_samples, d)
            The demonstrations; or positions of samples (one row each), with ``y``.
        y : array, shape (n_samples, d), optional
            Velocities at the rows of ``X`` (only with an array ``X``). Samples have no time
            order, so the Eq. 11 weights are uniform; prefer :class:`Demonstrations` for the
            direction objective. This form is what scikit-learn's model selection passes
            (split by demonstration, e.g. ``GroupKFold``).
        target : array, shape (d,), optional
            The attractor for array input (default: the origin).

        Returns
        -------
        self : SEDS
            Fitted: ``model_`` is the certified :class:`StableDS` (``model_.fit_info`` holds the
            solver status, iterations, objective and time; also ``fit_info_``).

        Raises
        ------
        SolverError
            IPOPT failed (or did not converge and ``require_convergence`` is set).
        StabilityError
            The solution failed the Eq. 10 certificate (never expected by construction; the check
            is there so that an uncertified model can never be returned).
        """
        demos = _as_demonstrations(X, y, target)
        params = self._validated()
        self.model_ = self._solve(demos, params)
        self.fit_info_ = self.model_.fit_info
        self.n_features_in_ = demos.n_dims
        return self

    def predict(self, X) -> np.ndarray:
        """f(x) of Eq. 5 of the fitted model at each point (see :meth:`StableDS.predict`)."""
        return self._fitted().predict(X)

    def score(self, X, y=None, sample_weight=None) -> float:
        """R^2 of the predicted velocities (scikit-learn's regressor score).

        ``X`` is a :class:`Demonstrations` (then ``y`` is taken from it) or positions with
        velocities ``y``.
        """
        from sklearn.metrics import r2_score

        if isinstance(X, Demonstrations):
            Xs, Xd, _, _ = X.stacked()
            X, y = Xs + X.target, Xd
        return float(r2_score(y, self.predict(X), sample_weight=sample_weight))

    def _fitted(self) -> StableDS:
        model = getattr(self, "model_", None)
        if model is None:
            from sklearn.exceptions import NotFittedError

            raise NotFittedError("this SEDS learner is not fitted yet: call fit(demos) first")
        return model

    def _solve(self, demos: Demonstrations, params: dict) -> StableDS:
        t0 = time.perf_counter()
        prob = self.build_problem(demos)
        opts = {
            "print_time": False,
            "ipopt.print_level": 5 if self.verbose else 0,
            "ipopt.sb": "yes",
            "ipopt.max_iter": params["max_iter"],
            "ipopt.tol": self.tol,
            # only simple bounds and an interior start: a small initial barrier parameter saves
            # about 40 % of the iterations on LASA at the same accuracy (measured, see README)
            "ipopt.mu_init": 1e-4,
            "ipopt.acceptable_tol": 1e-2,
            "ipopt.acceptable_obj_change_tol": params["tol_objective_change"],
            "ipopt.acceptable_iter": 5,
            "ipopt.hessian_approximation": self.hessian,
        }
        theta_sym = ca.MX.sym("theta", prob.layout.size)
        objective = prob.kernels.nlp_objective()  # keep alive while the solver runs
        nlp = {"x": theta_sym, "f": objective(theta_sym)}
        bounds = {}
        if params["approach_direction"] is not None:
            u = params["approach_direction"]
            if u.shape != (prob.layout.d,):
                raise ValueError(f"approach_direction has {u.shape[0]} entries for "
                                 f"{prob.layout.d}-D demonstrations")
            g = approach_constraints(prob.layout, prob.margin, u, self.approach_ratio)
            nlp["g"] = g(theta_sym)
            d = prob.layout.d
            bounds = {"lbg": np.zeros(2 * (d - 1)),
                      "ubg": np.r_[np.zeros(d - 1), np.full(d - 1, np.inf)]}
        solver = ca.nlpsol("seds", "ipopt", nlp, opts)
        t_built = time.perf_counter()
        res = solver(x0=prob.theta0, lbx=prob.lbx, ubx=prob.ubx, **bounds)
        stats = solver.stats()
        status = str(stats.get("return_status", "unknown"))
        theta = np.asarray(res["x"]).ravel()
        J = float(res["f"])
        if not (np.all(np.isfinite(theta)) and np.isfinite(J)):
            raise SolverError("IPOPT returned non-finite parameters or objective", status)
        converged = status in _OK_STATUS
        if not converged:
            msg = f"IPOPT stopped without converging after {stats.get('iter_count')} iterations"
            if self.require_convergence:
                raise SolverError(msg, status)
            warnings.warn(f"{msg} (status {status}); the model is certified stable but may fit "
                          "poorly. Raise max_iter or check the data.", ConvergenceWarning,
                          stacklevel=3)
        c = prob.speed_factor(theta) if self.objective == "direction" else 1.0
        priors, means, covs = prob.to_model_arrays(theta, speed_factor=c)
        info = {
            "status": status,
            "success": converged,
            "iterations": int(stats.get("iter_count", -1)),
            "objective": J,
            "objective_initial": prob.kernels.value(prob.theta0),
            "objective_name": self.objective,
            "seconds": time.perf_counter() - t0,
            "seconds_solve": time.perf_counter() - t_built,
            "n_parameters": prob.layout.size,
            "speed_factor": c,
            "n_components": params["n_components"],
            "n_samples": int(prob.X.shape[0]),
            "hessian": self.hessian,
            "compiled_kernels": prob.kernels.compiled,
            "solver": "ipopt",
        }
        return StableDS(priors, means, covs, prob.target, fit_info=info, status=status)


def _as_demonstrations(X, y, target) -> Demonstrations:
    """Demonstrations from fit()'s input (a Demonstrations, or sample arrays X, y)."""
    if isinstance(X, Demonstrations):
        if y is not None or target is not None:
            raise ValueError("y and target are taken from the Demonstrations; pass them only "
                             "with array input")
        return X
    if y is None:
        raise TypeError(
            f"fit expects a seds_casadi.Demonstrations, or sample arrays X (positions) and y "
            f"(velocities); got {type(X).__name__} without y. Wrap trajectories with "
            "Demonstrations(positions, dt=...)"
        )
    return Demonstrations.from_samples(X, y, target=target)
