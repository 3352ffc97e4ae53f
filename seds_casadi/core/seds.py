"""SEDS: learn a globally stable GMM dynamical system, built in CasADi and solved by IPOPT.

The problem (paper Section 4.1, Eq. 4-11; original objectives of Khansari-Zadeh and Billard 2011)

    min_theta J(theta)   subject to Eq. 10 (a)-(e)

is written symbolically in CasADi (SX) with the constraints satisfied by construction (see
:mod:`seds_casadi.core.parametrization`) and solved by IPOPT with exact gradients and exact Hessians
from algorithmic differentiation. After every solve the model is certified numerically
(:func:`seds_casadi.core.stable_ds.certify`); a model that fails is never returned.
"""

from __future__ import annotations

import dataclasses
import logging
import threading
import time
import warnings

import casadi as ca
import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin

from ._random import sklearn_random_state
from ._signals import deferred_interrupts
from .demonstrations import Demonstrations
from .errors import ConvergenceWarning, SEDSError, SolverError, StabilityError
from .lyapunov import estimate_lyapunov
from .model_selection import (
    bic_n_components,
    choose_by_reproduction,
    peak_speed_factor,
    speed_penalty,
)
from .objectives import approach_constraints
from .parametrization import Layout, stability_constraints
from .problem import SEDSProblem, build_problem, data_scales, pc_embedding, prefetch_labels
from .report import warn_ends_apart
from .search import held_out_scores
from .settings import (
    AUTO,
    AUTO_K_RANGE,
    PARAMETER_CONSTRAINTS,
    Hessian,
    Init,
    SEDSSettings,
    SettingsError,
)
from .stable_ds import StableDS
from .strength import StrengthFactor, StrengthFactorLearner
from .user_constraints import UserConstraints

_LOG = logging.getLogger(__name__)
_OK_STATUS = ("Solve_Succeeded", "Solved_To_Acceptable_Level")
#: largest NLP constraint violation of a fit taken as feasible (IPOPT's constr_viol_tol here)
_FEASIBLE = 1e-8
#: seconds between two progress lines of a running fit (logging, INFO)
PROGRESS_SECONDS = 2.0
#: taper radius r of a strength model (:class:`StableDS`), as a fraction of the data's extent:
#: the speed falls within about r of the target (the LASA protocols call 1 % "reached")
STRENGTH_RADIUS = 0.01
#: samples slower than this times the median speed (the demonstrations' ends) are left out of
#: the strength factor's GMM: their log speeds would stretch its range towards -inf
STRENGTH_MIN_SPEED = 0.02
#: ... and at least the distance covered at the speed v(x*) in this many of the data's steps
STRENGTH_STEPS = 2.0
#: ... and at most this fraction of the extent
STRENGTH_RADIUS_MAX = 0.25


class _Progress(ca.Callback):
    """IPOPT's iteration callback: a log line (INFO) at most every PROGRESS_SECONDS, and a stop
    request (IPOPT's ``User_Requested_Stop``) once an interrupt is pending.

    CasADi catches what a callback raises: a ``KeyboardInterrupt`` raised here would end the
    solve as ``NonIpopt_Exception_Thrown`` and never reach the caller. The signals' exceptions
    are held by :class:`~seds_casadi.core._signals.deferred_interrupts` around the solve
    (``interrupt``) and raised after it; one raised here all the same (no handler could be held,
    e.g. one installed from C) is remembered in :attr:`interrupted` and raised after the solve.
    """

    def __init__(self, nx: int, ng: int, label: str) -> None:
        ca.Callback.__init__(self)
        self.nx, self.ng, self.label = nx, ng, label
        self.iteration, self.t0 = 0, time.perf_counter()
        self._last = self.t0
        self.interrupt: deferred_interrupts | None = None
        self.interrupted = False
        self.construct("seds_progress", {})

    def restart(self, label: str) -> None:
        """Count and time a new solve (a cached solver's callback is used again)."""
        self.label, self.iteration, self.t0 = label, 0, time.perf_counter()
        self._last, self.interrupt, self.interrupted = self.t0, None, False

    def get_n_in(self):
        return ca.nlpsol_n_out()

    def get_n_out(self):
        return 1

    def get_name_in(self, i):
        return ca.nlpsol_out(i)

    def get_name_out(self, i):
        return "ret"

    def get_sparsity_in(self, i):
        name = ca.nlpsol_out(i)
        if name == "f":
            return ca.Sparsity.scalar()
        if name in ("x", "lam_x"):
            return ca.Sparsity.dense(self.nx)
        if name in ("g", "lam_g"):
            return ca.Sparsity.dense(self.ng)
        return ca.Sparsity(0, 0)

    def eval(self, arg):
        try:
            if self.interrupted or (self.interrupt is not None and self.interrupt.pending):
                return [1]
            self.iteration += 1
            now = time.perf_counter()
            if now - self._last >= PROGRESS_SECONDS:
                self._last = now
                _LOG.info("%s: iteration %d, objective %.6g, %.1f s", self.label,
                          self.iteration, float(arg[1]), now - self.t0)
            return [0]
        except KeyboardInterrupt:
            self.interrupted = True
            return [1]


# ------------------------------------------------------------------ the learner
class SEDS(RegressorMixin, BaseEstimator):
    """Stable Estimator of Dynamical Systems, in CasADi + IPOPT.

    ``n_components`` may be given by position, every other parameter by keyword. Each parameter's
    allowed types and values are declared once (``_parameter_constraints``, from
    :data:`~seds_casadi.core.settings.PARAMETER_CONSTRAINTS`) and checked by :meth:`fit` before
    any work, together with the settings that do not go together
    (:meth:`~seds_casadi.core.settings.SEDSSettings.from_params`): a bad value raises a
    ``ValueError`` (scikit-learn's ``InvalidParameterError``, also a ``TypeError``) naming the
    parameter and what it accepts.

    With no settings (every ``"auto"`` default), ``SEDS()`` uses the measured best settings
    (:data:`~seds_casadi.core.settings.BEST_SETTINGS`: ``objective="mse", init="pc",
    gmm="fixed", lyapunov="learned", gain_limit=10``) and chooses K itself; a setting given
    overrides its own entry, and naming the objective (or giving an arrival constraint,
    constraints of one's own or the constrained form) gives SEDS's own settings for the rest
    (:data:`~seds_casadi.core.settings.CLASSIC_SETTINGS`: P = I, joint EM, joint fit, no gain
    limit, K = 5). ``fit_info["choice"]`` says what was chosen and why.

    Parameters
    ----------
    n_components : int, sequence of int, "auto" or "bic", default "auto"
        Number K of Gaussians. ``"auto"``: with the automatic settings, the K in 4-10 whose
        reproductions of the demonstrations fit them best
        (:func:`~seds_casadi.core.model_selection.choose_by_reproduction`; it fits 4, 7 and 10,
        then the neighbours of the best-scoring K until its neighbours are all tried), else 5.
        A sequence: the K tried by the same criterion, exactly those. ``"bic"`` picks K in
        1..15 by the BIC of a GMM on [x; xdot] at the elbow of the BIC curve, as ds-opt does
        (:func:`~seds_casadi.core.model_selection.bic_n_components`; on smooth data the BIC
        minimum lies at the largest K tried; the scores are in ``fit_info["bic"]``).
        :class:`~seds_casadi.core.search.DemoSearchCV` (held-out demonstrations, reproduced and
        scored) or ``GridSearchCV`` over K are the held-out alternatives.
    objective : {"auto", "direction", "mse", "likelihood"}, default "auto"
        ``"auto"``: ``"mse"`` with the automatic settings. ``"direction"``: the paper's Eq. 9
        (weighted cosine between demonstrated and model velocities, weights of Eq. 11); ``"mse"``
        and ``"likelihood"``: the original SEDS objectives (mean squared velocity error; negative
        log-likelihood of the joint GMM).
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
    hessian : {"auto", "exact", "limited-memory"}, default "auto"
        Exact Hessians by algorithmic differentiation, or IPOPT's L-BFGS approximation (with
        exact gradients). ``"auto"``: exact up to 80 parameters (2-D up to K = 8, 3-D up to
        K = 4; the hitting motion's K = 3), L-BFGS above, where the exact Hessian's C kernel
        takes a minute or more to compile (its fits are less accurate: force ``"exact"`` when
        time allows).
        ``fit_info["hessian"]`` says which was used.
    require_convergence : bool, default False
        If True, an IPOPT run that stops without converging raises :class:`SolverError`; if False
        it gives a :class:`ConvergenceWarning` and returns the (certified) model, with the status in
        ``fit_info``.
    compile : bool, default True
        Compile the per-sample kernels to C when a C compiler is found (cached on disk; see
        :mod:`seds_casadi.codegen`); otherwise CasADi's virtual machine evaluates them.
    approach_direction : array, shape (d,), optional
        If given, constrain the model so that this direction is the slowest way into the target,
        with motion across it at least ``approach_ratio`` times faster (an extension of the paper
        for hitting motions; see :func:`seds_casadi.core.objectives.approach_constraints`).
    approach_ratio : float, default 4.0
    lyapunov : {"auto", "identity", "learned"}, default "auto"
        ``"auto"``: ``"learned"`` with the automatic settings, else ``"identity"``. The Lyapunov
        function that certifies the model. ``"identity"``: SEDS's
        V(x) = |x - x*|^2 (A_k + A_k^T < 0). ``"learned"``: V(x) = (x - x*)^T P (x - x*) with a
        symmetric positive definite P optimised jointly with the GMM (A_k^T P + P A_k < 0, the
        condition of LPV-DS), which lets the model follow motions that first move away from the
        target; starts from :func:`~seds_casadi.core.lyapunov.estimate_lyapunov`. The fitted
        model exposes P as ``model_.lyapunov_matrix``.
    formulation : {"by-construction", "constrained"}, default "by-construction"
        How Eq. 10 is imposed: by the parametrization (every IPOPT iterate is a stable model), or
        as the paper and the original SEDS code state it, constraints of the NLP (free A_k,
        leading principal minors, mu_xdot and prior-sum equalities) handled by IPOPT's
        interior-point method (:func:`~seds_casadi.core.parametrization.stability_constraints`).
        Both are certified after the solve.
    constraints : callable, optional
        Extra constraints of the user's own: ``constraints(model) -> [(g, lower, upper), ...]``
        where ``model`` is a dict of CasADi SX expressions in the caller's units:
        ``"priors"`` (K, 1), ``"mu_x"``, ``"A"`` and ``"Sigma_x"`` (lists over components of
        (d, 1), (d, d), (d, d)), ``"P"`` (d, d) and ``"target"`` (numpy). Each ``g`` is a scalar
        or column expression with numeric bounds (use ``-inf``/``inf`` for one-sided ones).
        They are constraints of the NLP, and the returned model is checked against them
        (``fit_info["user_constraint_violation"]``; a violation beyond 1e-6 raises
        :class:`SolverError`). With the direction objective the gains are rescaled after the
        solve (``fit_info["speed_factor"]``), so constraints on the scale of ``A`` need
        ``objective="mse"`` or ``"likelihood"``.
    speed_calibration : {"strength", "median", "least-squares"}, default "strength"
        How a direction-objective model gets the demonstrated speeds (Eq. 9 fixes only
        directions; ignored by the other objectives, which fit speeds):

        * ``"strength"``: the paper's way (Eq. 3, 8, 12): a strength factor v(x) > 0 learned by
          GMR of the demonstrated log speeds on the positions (:class:`StrengthFactor`, with
          ``strength_components`` Gaussians) sets the speed along the certified streamlines;
          the returned :class:`StableDS` moves at ``v(x)`` in the direction of f, slowing down
          near the target (within 1 % of the data's extent, or more for motions that arrive
          fast: see :meth:`_fit_strength` and :class:`StableDS`). Same
          streamlines, same certificate. Without it a model's speed can collapse along part of
          the path (on LASA WShape, Leaf_2 and Angle, reproductions did not arrive within 3x
          the demonstration's duration; measured in ``benchmarks/README.md``).
        * ``"median"``: one factor c on every A_k, making the median speed ratio along the
          demonstrations 1 (:meth:`SEDSProblem.speed_factor`); the model stays a plain GMM DS
          (Eq. 5).
        * ``"least-squares"``: the least-squares factor (dominated by the samples where ||f||
          is largest; the default before the median).
    strength_components : int or None, default None
        Gaussians of the strength factor's GMM (``speed_calibration="strength"``); None: the
        model's own K.
    gain_limit : float, None or "auto", default "auto"
        ``"auto"``: 10 with the automatic settings, else None. Bound the stiffness of the
        components: the entries of B_k within +-sqrt(g) and of W_k within +-g
        (A_k = -(B_k B_k^T + m I) + W_k - W_k^T; constrained form: the entries of A_k within
        +-d g), in the scaled frame where positions and velocities have unit RMS, so every
        |eigenvalue of A_k| stays within about d g times the data's own rate. Without it a thin
        component can reach rates of hundreds per second that explicit integrators at the data's
        step cannot follow (on LASA, forward Euler at 0.01 s diverged from a rate of 540/s).
        None: unbounded, as SEDS (measured in ``benchmarks/README.md``). The value is
        data-dependent: 10 suited LASA, but a bound can also keep IPOPT from the better fit.
    init : {"auto", "joint-em", "lpv", "pc"}, default "auto"
        ``"auto"``: ``"pc"`` with the automatic settings, else ``"joint-em"``. IPOPT's starting
        point. ``"joint-em"`` (SEDS's): k-means + EM on [x; xdot], each
        component's regression gain projected onto the stable set. ``"lpv"`` (LPV-DS's, Figueroa
        and Billard 2018, first two steps): EM on the positions alone, then the gains of least
        velocity error under that GMM's mixing, stable for the initial P (a small IPOPT problem
        whose size does not depend on the number of samples); the joint problem then improves on
        it. The problem is non-convex, so the start decides which optimum is reached; which one
        is better depends on the data (compared on LASA in ``benchmarks/README.md``).
        ``"pc"``: as ``"lpv"``, with the GMM on the positions from a *physically-consistent*
        clustering (PC-GMM's similarity, Figueroa and Billard 2018: samples are alike when they
        are close and move the same way; :func:`~seds_casadi.core.problem.pc_similarity`),
        cut into ``n_components`` clusters by spectral clustering; each cluster then follows
        one locally linear piece of the motion. PC-GMM samples a Dirichlet-process mixture and
        so also chooses K; here K stays the learner's (choose it with :class:`DemoSearchCV`).
    gmm : {"auto", "joint", "fixed"}, default "auto"
        ``"auto"``: ``"fixed"`` with the automatic settings, else ``"joint"``. ``"joint"`` (SEDS,
        Eq. 10): IPOPT optimises the GMM and the dynamics together.
        ``"fixed"``: the priors, means and position covariances keep the values of ``init``
        and IPOPT optimises the dynamics (the A_k and, with ``lyapunov="learned"``, P) under
        that fixed mixing, as LPV-DS does after its clustering; the model is certified the
        same way. With ``init="pc"`` this is what generalised best on LASA's held-out demos
        (``benchmarks/README.md``): optimising the GMM too fits the training demos closer and
        moves the components off the pieces of the motion they stood for.
    solver_options : dict or None, default None
        Extra IPOPT options, by IPOPT's names (``{"mu_strategy": "adaptive"}``; the ``ipopt.``
        prefix is added), over the learner's own (``_ipopt_options``), except
        ``hessian_approximation``, which ``hessian`` sets. Every model is certified after the
        solve whatever the options. ``mu_strategy="adaptive"`` is measured in
        ``benchmarks/README.md``: on the ds-opt LASA protocol it cut the median fit time, but
        not on every shape.
    verbose : bool, default False
        Print IPOPT's iteration log.
    """

    _parameter_constraints: dict = PARAMETER_CONSTRAINTS

    def __init__(
        self,
        n_components: int | str = AUTO,
        *,
        objective: str = AUTO,
        random_state=None,
        omega_lower: float = 1.0,
        omega_upper: float = 2.0,
        stability_margin: float = 1e-3,
        max_iter: int = 1000,
        tol: float = 1e-6,
        tol_objective_change: float = 1e-5,
        hessian: str = "auto",
        require_convergence: bool = False,
        compile: bool = True,
        approach_direction=None,
        approach_ratio: float = 4.0,
        lyapunov: str = AUTO,
        formulation: str = "by-construction",
        constraints=None,
        speed_calibration: str = "strength",
        strength_components: int | None = None,
        gain_limit: float | str | None = AUTO,
        init: str = AUTO,
        gmm: str = AUTO,
        solver_options: dict | None = None,
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
        self.lyapunov = lyapunov
        self.formulation = formulation
        self.constraints = constraints
        self.speed_calibration = speed_calibration
        self.strength_components = strength_components
        self.gain_limit = gain_limit
        self.init = init
        self.gmm = gmm
        self.solver_options = solver_options
        self.verbose = verbose

    def _settings(self, demos) -> SEDSSettings:
        """The settings of a fit from the parameters (checked by ``_validate_params`` first),
        checked together and against the data's dimension (``n_components`` None for
        ``"bic"``)."""
        return SEDSSettings.from_params(
            self.get_params(deep=False),
            n_dims=demos.n_dims if isinstance(demos, Demonstrations) else None)

    def build_problem(self, demos: Demonstrations, n_components: int | None = None
                      ) -> SEDSProblem:
        """Scale the data, initialise by k-means + EM and build the CasADi problem (to solve,
        or to inspect: objective, gradient and Hessian at any parameter vector).

        ``n_components`` overrides the learner's (with ``"bic"``, K is otherwise chosen on the
        data as :meth:`fit` does)."""
        self._validate_params()
        settings = self._settings(demos)
        if n_components is not None:
            settings = settings.with_components(int(n_components))
        elif settings.k_candidates is not None:
            raise SettingsError(
                f"K is chosen by fitting each of {list(settings.k_candidates)} "
                "(n_components='auto' or a sequence): pass the K to build, "
                "build_problem(demos, n_components=K)")
        elif settings.problem.n_components is None and isinstance(demos, Demonstrations):
            settings = self._choose_components(demos, settings)[0]
        return build_problem(demos, settings.problem)

    def _choose_components(self, demos: Demonstrations, settings: SEDSSettings
                           ) -> tuple[SEDSSettings, np.ndarray]:
        """K by BIC (``n_components="bic"``): the settings with K, and the BIC curve."""
        Xs, Xd, _, _ = demos.stacked()
        K, bic = bic_n_components(Xs, Xd, random_state=settings.problem.random_state)
        return settings.with_components(K), bic

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
        ValueError, TypeError
            A parameter out of its declared range, or settings that do not go together (before
            any work; scikit-learn's ``InvalidParameterError`` is both).
        SolverError
            IPOPT failed (or did not converge and ``require_convergence`` is set).
        StabilityError
            The solution failed the Eq. 10 certificate (never expected by construction; the check
            is there so that an uncertified model can never be returned).
        """
        self._validate_params()
        demos = _as_demonstrations(X, y, target)
        settings = self._settings(demos)
        _check_solver_options(settings)
        if settings.k_candidates is not None:
            candidates = self._supported_candidates(demos, settings)
            pool = self._refinement_pool(demos, settings)
        warn_ends_apart(demos, stacklevel=2)
        t0 = time.perf_counter()
        bic = None
        if settings.k_candidates is not None:
            self.model_ = self._fit_candidates(demos, settings, candidates, pool)
        else:
            if settings.problem.n_components is None:
                settings, bic = self._choose_components(demos, settings)
            self.model_ = self._solve(demos, settings)
        if bic is not None:
            self.model_.fit_info["bic"] = bic.tolist()
        info = self.model_.fit_info
        info.setdefault("choice", {})
        info["choice"].update(settings=dict(settings.choice),
                              seconds=time.perf_counter() - t0)
        self.fit_info_ = info
        self.n_features_in_ = demos.n_dims
        return self

    def _supported_candidates(self, demos: Demonstrations, settings: SEDSSettings
                              ) -> tuple[int, ...]:
        """The K to try that the data supports (at least 2 samples per component and one
        velocity value per parameter, as :func:`build_problem` asks); a K the user listed that
        the data cannot support, or data that cannot be reproduced, is refused here, before
        any solve."""
        if not demos.time_ordered:
            raise SettingsError(
                "choosing K (n_components='auto' or a sequence) reproduces each demonstration "
                "from its start, and these samples have no time order: give n_components, or "
                "pass the trajectories as Demonstrations")
        n, d = demos.n_samples, demos.n_dims
        ok = tuple(K for K in settings.k_candidates if _supports(demos, settings, K))
        if settings.choice.get("n_components", "").startswith("given"):
            if len(ok) < len(settings.k_candidates):
                bad = [K for K in settings.k_candidates if K not in ok]
                raise SettingsError(
                    f"{n} samples in {d}-D are too few for K = {bad} of the K listed in "
                    "n_components; list smaller K or record more demonstrations")
            return ok
        if len(ok) < len(settings.k_candidates):  # the default grid, too large for the data:
            # also the largest K it supports (or the 3 largest below the grid)
            supported = [K for K in range(1, max(settings.k_candidates) + 1)
                         if _supports(demos, settings, K)]
            ok = tuple(sorted(set(ok) | set(supported[-1:]))) if ok else tuple(supported[-3:])
        if not ok:
            raise SettingsError(f"{n} samples in {d}-D are too few for any K; record more "
                                "demonstrations")
        return ok

    @staticmethod
    def _refinement_pool(demos: Demonstrations, settings: SEDSSettings) -> tuple[int, ...]:
        """The K the default choice may add around its best candidate: every K of
        :data:`~seds_casadi.core.settings.AUTO_K_RANGE` the data support (none when the user
        listed the K to try)."""
        if settings.choice.get("n_components", "").startswith("given"):
            return ()
        lo, hi = AUTO_K_RANGE
        return tuple(K for K in range(lo, hi + 1) if _supports(demos, settings, K))

    def _fit_candidates(self, demos: Demonstrations, settings: SEDSSettings,
                        candidates: tuple[int, ...], pool: tuple[int, ...] = ()) -> StableDS:
        """Fit each K of ``candidates`` to all demonstrations and keep the one whose
        reproductions of them score best (:func:`choose_by_reproduction`); the spectral
        embedding of ``init="pc"`` is computed once for all.

        With a ``pool`` (the default choice), the neighbours K - 1 and K + 1 in the pool of
        the best-scoring K so far are fitted too, until the best one's neighbours have all
        been tried: the grid finds the region, the neighbours its best K (on a 3-D helix
        the grid 4, 7, 10 scored 0.30 / 0.15 / 0.16 and K = 8, found this way, 0.11)."""
        seed = sklearn_random_state(settings.problem.random_state)  # one seed for every K
        embedding = lyapunov0 = None  # neither depends on K: computed once for all
        X, Xd, _, _ = demos.stacked()
        sx, sv = data_scales(X, Xd)
        if sx > 0 and sv > 0:
            if settings.problem.init is Init.PC:
                embedding = pc_embedding(X / sx, Xd / sv, max(candidates + pool), seed)
            if settings.problem.learned_lyapunov:
                lyapunov0 = estimate_lyapunov(X / sx, Xd / sv)
        fitted, metrics, table, ratios = {}, {}, {}, {}
        demo_peaks = np.array([np.linalg.norm(v, axis=1).max() for v in demos.velocities])
        # each K's clusters computed in the background while the K before it is fitted
        cancel = prefetch_labels(embedding, candidates) if embedding is not None else None
        try:
            self._fit_each(demos, settings, candidates, seed, embedding, lyapunov0, demo_peaks,
                           fitted, metrics, table, ratios)
            tried = set(candidates)
            while pool:
                best = _best_candidate(metrics, ratios)
                new = tuple(K for K in (best - 1, best + 1) if K in pool and K not in tried
                            ) if best is not None else ()
                if not new:
                    break
                tried.update(new)
                self._fit_each(demos, settings, new, seed, embedding, lyapunov0, demo_peaks,
                               fitted, metrics, table, ratios)
        finally:
            if cancel is not None:
                cancel()
        order = tuple(sorted(tried))
        return self._choose(order, fitted, metrics, {K: table[K] for K in order}, ratios,
                            refined=bool(pool))

    def _fit_each(self, demos, settings, candidates, seed, embedding, lyapunov0, demo_peaks,
                  fitted, metrics, table, ratios) -> None:
        """Fit each K of ``candidates`` and score its reproductions (into the dicts given)."""
        for K in candidates:
            t0 = time.perf_counter()
            s_k = settings.with_components(K)
            s_k = dataclasses.replace(s_k, problem=dataclasses.replace(s_k.problem,
                                                                       random_state=seed))
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                try:
                    model = self._solve(demos, s_k, embedding=embedding, lyapunov0=lyapunov0)
                    sc = held_out_scores(model, demos)
                except SEDSError as exc:
                    table[K] = {"error": str(exc), "seconds": time.perf_counter() - t0}
                    metrics[K] = None
                    continue
            r = _peak_ratios(sc, demo_peaks)
            c = peak_speed_factor(r) if model.strength is None else None
            if c is not None:  # it rushes at a common factor: its time scale, slowed (same paths)
                slowed = _time_scaled(model, c)
                sc_c = held_out_scores(slowed, demos)
                r_c = _peak_ratios(sc_c, demo_peaks)
                if speed_penalty(r_c) < speed_penalty(r):
                    model, sc, r = slowed, sc_c, r_c
                else:
                    c = None
            fitted[K] = (model, caught)
            metrics[K] = (sc["rmse"], sc["e_dot"], sc["dtw"])
            ratios[K] = r
            table[K] = {"rmse": sc["rmse"], "e_dot": sc["e_dot"], "dtw": sc["dtw"],
                        "peak_speed_ratios": ratios[K].tolist(), "time_scale": c,
                        "seconds": time.perf_counter() - t0}

    @staticmethod
    def _choose(candidates, fitted, metrics, table, ratios, refined: bool = False) -> StableDS:
        """The candidate :func:`choose_by_reproduction` keeps, with the choice in its
        ``fit_info``."""
        if not fitted:
            raise SolverError("no candidate K gave a certified model: "
                              + "; ".join(f"K={K}: {v['error']}" for K, v in table.items()),
                              "no candidate")
        K, score = choose_by_reproduction(metrics, speed_ratios=ratios)
        for k, v in score.items():
            table[k]["score"] = v
        model, caught = fitted[K]
        for w in caught:  # the chosen fit's warnings reach the caller
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
        rng = (min(candidates), max(candidates))
        model.fit_info["choice"] = {
            "n_components": K, "candidates": {int(k): v for k, v in table.items()},
            "rule": (("the K of the grid, then the neighbours of the best-scoring K until its "
                      "neighbours are tried too; of those, " if refined else "")
                     + "the smallest K whose reproductions of the demonstrations score within "
                     "5 % of the best (geometric mean of RMSE, e_dot and DTW, times a penalty "
                     "for peak speeds outside 0.8-1.25x the demonstrations'; "
                     "model_selection.choose_by_reproduction); a candidate whose reproductions "
                     "all peak too fast is first slowed by one factor "
                     "(model_selection.peak_speed_factor)"),
            "range": list(rng), "at_edge": bool(len(candidates) > 1 and K in rng
                                                and not (K == rng[0] and rng[0] == 1)),
        }
        _LOG.info("SEDS: K = %d chosen among %s (%.1f s)", K, list(candidates),
                  sum(v["seconds"] for v in table.values()))
        return model

    def report(self, demos: Demonstrations, **kwargs):
        """How well the fitted model reproduces ``demos`` (:func:`~seds_casadi.core.report.fit_report`:
        per demonstration, whether the reproduction from its start reaches the target, its
        duration and peak speed against the demonstration's, RMSE, e_dot and DTW; warnings)."""
        from .report import fit_report

        return fit_report(self._fitted(), demos, **kwargs)

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

    @staticmethod
    def _ipopt_options(settings: SEDSSettings, hessian: Hessian, constrained: bool = False
                       ) -> dict:
        opts = {
            "print_time": False,
            "ipopt.print_level": 5 if settings.verbose else 0,
            "ipopt.sb": "yes",
            "ipopt.max_iter": settings.max_iter,
            "ipopt.tol": settings.tol,
            # only simple bounds and an interior start: a small initial barrier parameter saves
            # about 40 % of the iterations on LASA at the same accuracy (measured, see README)
            "ipopt.mu_init": 1e-4,
            "ipopt.acceptable_tol": 1e-2,
            "ipopt.acceptable_obj_change_tol": settings.ipopt_objective_change_tol,
            "ipopt.acceptable_iter": 5,
            "ipopt.hessian_approximation": hessian.value,
        }
        if constrained:
            # Eq. 10 as constraints, the arrival constraint or the user's: IPOPT's iterates
            # satisfy them only at convergence, so an early "acceptable" stop must be feasible
            # to the certificate's precision (with the default 1e-2, an arrival-constraint fit
            # once stopped 5e-5 infeasible)
            opts["ipopt.constr_viol_tol"] = 1e-9
            opts["ipopt.acceptable_constr_viol_tol"] = 1e-9
        for k, v in settings.solver_options.items():
            opts[k if k.startswith("ipopt.") else f"ipopt.{k}"] = v
        return opts

    @staticmethod
    def _constraints(prob: SEDSProblem, settings: SEDSSettings, theta_sym
                     ) -> tuple[list, list, list, UserConstraints | None]:
        """Constraints of the NLP: the optional arrival constraint, Eq. 10 in the constrained
        form, the user's own; as (expressions, lbg, ubg, user)."""
        g, lb, ub = [], [], []
        u = settings.approach_direction
        d = prob.layout.d
        if u is not None:
            fa = approach_constraints(prob.layout, prob.margin, u, settings.approach_ratio)
            g.append(fa(theta_sym))
            lb.append(np.zeros(2 * (d - 1)))
            ub.append(np.r_[np.zeros(d - 1), np.full(d - 1, np.inf)])
        if prob.layout.constrained:
            fs, lbs, ubs = stability_constraints(prob.layout, prob.margin)
            g.append(fs(theta_sym))
            lb.append(lbs)
            ub.append(ubs)
        user = None
        if settings.constraints is not None:
            try:
                user = UserConstraints(settings.constraints, prob)
            except (NotImplementedError, RuntimeError) as exc:  # CasADi refused what it returned
                raise TypeError(
                    "constraints(model) must return [(g, lower, upper), ...] with each g a "
                    "CasADi expression (or number) of the model's entries and numeric bounds; "
                    f"CasADi could not use what it returned: {str(exc).splitlines()[0]}"
                ) from None
            g.append(user.of_theta(theta_sym))
            lb.append(user.lower)
            ub.append(user.upper)
        return g, lb, ub, user

    def _solve(self, demos: Demonstrations, settings: SEDSSettings, embedding=None,
               lyapunov0=None) -> StableDS:
        t0 = time.perf_counter()
        ps = settings.problem
        strength = radius = None  # first: data it cannot use is refused before the long solve
        if settings.fits_strength:
            strength, radius = self._fit_strength(demos, settings)
        prob = build_problem(demos, ps, embedding=embedding, lyapunov0=lyapunov0)
        theta_sym = ca.MX.sym("theta", prob.layout.size)
        # CasADi calls our Python callbacks (construction, derivatives, iterations) and turns
        # what they raise into its own errors: Ctrl-C / SIGTERM are held until the block ends
        # (IPOPT stops at its next iteration once one is pending; see _run)
        with deferred_interrupts():
            g, lbg, ubg, user = self._constraints(prob, settings, theta_sym)
            parametric = getattr(prob.kernels, "nlp_parametric", None)
            data, cache_key = {}, None
            if parametric is not None and not g:
                # J's SX expression itself, the data's statistics as parameters: CasADi builds
                # its exact Hessian about twice as fast as through an MX call of the same
                # Function (2-D LASA, K = 10: 0.045 against 0.096 s set-up), and the solver is
                # built once per process for each (K, d, margin, options) (_SOLVERS)
                theta_sx, p_sx, J_sx, sym_key = parametric()
                nlp = {"x": theta_sx, "p": p_sx, "f": J_sx}
                data = {"p": prob.kernels.parameters}
                cache_key = (sym_key, repr(sorted(self._ipopt_options(
                    settings, prob.hessian).items())))
            else:
                objective = prob.kernels.nlp_objective()  # keep alive while the solver runs
                nlp = {"x": theta_sym, "f": objective(theta_sym)}
            bounds = {}
            if g:
                nlp["g"] = ca.vertcat(*g)
                bounds = {"lbg": np.concatenate(lbg), "ubg": np.concatenate(ubg)}
            label = (f"SEDS fit ({ps.objective}, K={prob.layout.K}, d={prob.layout.d}, "
                     f"{prob.layout.formulation}, P {prob.layout.lyapunov}, "
                     f"{prob.X.shape[0]} samples, {prob.layout.size} parameters, "
                     f"{prob.hessian} Hessian)")
            _LOG.info("%s: solving with IPOPT (problem built in %.1f s)", label,
                      time.perf_counter() - t0)
            cached = _take_solver(cache_key)
            if cached is not None:
                solver, progress = cached
                progress.restart(label)
            else:
                progress = _Progress(prob.layout.size, int(nlp["g"].numel()) if "g" in nlp
                                     else 0, label)
            opts = dict(self._ipopt_options(settings, prob.hessian, constrained=bool(g)),
                        iteration_callback=progress)
            try:
                if cached is None:
                    solver = ca.nlpsol("seds", "ipopt", nlp, opts)
            except RuntimeError as exc:
                if settings.solver_options and "option" in str(exc).lower():  # IPOPT printed the
                    # valid settings of a bad value above
                    raise ValueError(f"IPOPT refused solver_options {dict(settings.solver_options)!r}: "
                                     f"{str(exc).splitlines()[-1].split(': ', 1)[-1]} (names as "
                                     "in IPOPT's documentation, e.g. 'mu_strategy')") from None
                raise
            t_built = time.perf_counter()
            g_fun = ca.Function("g", [theta_sym], [nlp["g"]]) if g else None

            def violation(theta) -> float:
                if g_fun is None:
                    return 0.0
                gv = np.asarray(g_fun(theta)).ravel()
                return float(np.max(np.r_[0.0, bounds["lbg"] - gv, gv - bounds["ubg"]]))

            res, stats = _run(solver, progress, x0=prob.theta0, lbx=prob.lbx, ubx=prob.ubx,
                              **bounds, **data)
            _keep_solver(cache_key, (solver, progress))  # after a solve that ended normally
            status = str(stats.get("return_status", "unknown"))
            theta = np.asarray(res["x"]).ravel()
            J = float(res["f"])
            if not (np.all(np.isfinite(theta)) and np.isfinite(J)):
                raise SolverError("IPOPT returned non-finite parameters or objective", status)
            viol = violation(theta)
            recovered = None
            if (status not in _OK_STATUS and viol > _FEASIBLE and prob.hessian == Hessian.EXACT
                    and "hessian_approximation" not in str(settings.solver_options)):
                # the exact Hessian of a constrained fit can stall infeasible (an arrival-constraint
                # fit ended 4e-5 infeasible after 1,000 iterations, and so did a warm start from
                # there with L-BFGS); the same fit from the start with L-BFGS: feasible to 1e-11
                # in 637 iterations. The feasible one of the two is kept.
                opts2 = dict(opts, **{"ipopt.hessian_approximation": "limited-memory"})
                solver2 = ca.nlpsol("seds_feasible", "ipopt", nlp, opts2)
                res2, stats2 = _run(solver2, progress, x0=prob.theta0, lbx=prob.lbx, ubx=prob.ubx,
                                    **bounds, **data)
                theta2 = np.asarray(res2["x"]).ravel()
                J2 = float(res2["f"])
                _LOG.info("%s: the exact-Hessian solve ended %.3g infeasible; with L-BFGS from the "
                          "start: %s, %.3g", label, viol, stats2.get("return_status"),
                          violation(theta2))
                if np.all(np.isfinite(theta2)) and np.isfinite(J2) and violation(theta2) < viol:
                    recovered = {"status": status, "iterations": int(stats.get("iter_count", -1)),
                                 "constraint_violation": viol}
                    theta, J, viol = theta2, J2, violation(theta2)
                    status = str(stats2.get("return_status", "unknown"))
                    stats = dict(stats2, iter_count=int(stats.get("iter_count", 0))
                                 + int(stats2.get("iter_count", 0)))
        converged = status in _OK_STATUS
        if viol > 1e-6 and settings.approach_direction is not None:
            raise SolverError(
                f"IPOPT ended {viol:.3g} outside the arrival constraint (approach_direction, "
                f"approach_ratio) after {stats.get('iter_count')} iterations: no model that "
                "breaks it is returned. Raise max_iter, lower approach_ratio, or use more "
                "components", status)
        if not converged:
            msg = f"IPOPT stopped without converging after {stats.get('iter_count')} iterations"
            if settings.require_convergence:
                raise SolverError(msg, status)
            warnings.warn(f"{msg} (status {status}); the model is certified stable but may fit "
                          "poorly. Raise max_iter or check the data.", ConvergenceWarning,
                          stacklevel=3)
        _LOG.info("%s: %s after %d iterations, %.1f s", label, status,
                  int(stats.get("iter_count", -1)), time.perf_counter() - t0)
        try:
            c = (prob.speed_factor(theta, settings.speed_calibration)
                 if settings.speed_calibration is not None else 1.0)
            priors, means, covs = prob.to_model_arrays(theta, speed_factor=c)
        except np.linalg.LinAlgError:
            raise SolverError(
                "the solution has a numerically singular covariance (a component collapsed "
                f"onto a subspace of the {prob.layout.d}-D data); use fewer components, more or "
                "less redundant data, or hessian='exact'", status) from None
        lyap = prob.lyapunov_matrix(theta) if ps.learned_lyapunov else None
        info = {
            "status": status, "success": converged,
            "lyapunov": ps.lyapunov.value, "formulation": ps.formulation.value,
            "init": ps.init.value, "gmm": ps.gmm.value,
            "constraint_violation": viol,
            "feasibility_pass": recovered,
            "iterations": int(stats.get("iter_count", -1)), "objective": J,
            "objective_initial": prob.kernels.value(prob.theta0),
            "objective_name": ps.objective.value, "seconds": time.perf_counter() - t0,
            "seconds_solve": time.perf_counter() - t_built, "n_parameters": prob.layout.size,
            "speed_factor": c, "n_components": ps.n_components,
            "speed_calibration": (None if settings.speed_calibration is None
                                  else settings.speed_calibration.value),
            "strength_components": None if strength is None else len(strength.priors),
            "n_samples": int(prob.X.shape[0]), "hessian": prob.hessian.value,
            "compiled_kernels": prob.kernels.compiled, "sums": prob.kernels.engine,
            "solver": "ipopt",
            "solver_options": dict(settings.solver_options),
        }
        try:
            model = StableDS(priors, means, covs, prob.target, fit_info=info, status=status,
                             lyapunov=lyap, strength=strength, strength_radius=radius)
        except StabilityError as exc:
            if not ps.constrained:
                raise
            raise SolverError(
                f"the constrained form ended at a point that violates Eq. 10 ({exc}; largest "
                f"NLP constraint violation {viol:.3g}): IPOPT found no feasible optimum. Raise "
                "max_iter, or use formulation='by-construction', which is stable at every "
                "iterate", status) from None
        if user is not None:
            model.fit_info["user_constraint_violation"] = user.check(model, status)
        return model

    @staticmethod
    def _fit_strength(demos: Demonstrations, settings: SEDSSettings
                      ) -> tuple[StrengthFactor, float]:
        """The strength factor (Eq. 12 in log speed) on the demonstrations' moving samples, and
        the taper radius r: :data:`STRENGTH_RADIUS` times the data's extent, or, if more, the
        distance covered at v(x*) in :data:`STRENGTH_STEPS` of the data's time steps (so that
        the taper's rate v(x*) / r is at most half the sampling rate), at most
        :data:`STRENGTH_RADIUS_MAX` times the extent."""
        Xs, Xd, _, _ = demos.stacked()
        speed = np.linalg.norm(Xd, axis=1)
        typical = float(np.median(speed[speed > 0])) if np.any(speed > 0) else 0.0
        moving = speed > STRENGTH_MIN_SPEED * typical
        n, need = int(np.count_nonzero(moving)), demos.n_dims + 2
        if n < need:
            raise ValueError(
                f"the demonstrations hardly move: {n} samples faster than {STRENGTH_MIN_SPEED:g} "
                f"x the median speed, and a strength factor (Eq. 12) over {demos.n_dims}-D "
                f"positions needs at least {need}; check the velocities, or use "
                "speed_calibration='median'")
        X = Xs[moving] + demos.target
        K = settings.strength_components or settings.problem.n_components
        Ksf = max(1, min(int(K), n // need))
        sf = StrengthFactorLearner(n_components=Ksf, random_state=settings.problem.random_state
                                   ).fit(X, speed[moving]).factor_
        extent = max(float(np.max(np.ptp(Xs, axis=0))), 1e-12)
        radius = STRENGTH_RADIUS * extent
        if demos.time_ordered:  # trajectories in time order have a step
            # the taper's rate v(x*) / r stays one that the data's own step can follow (motions
            # that arrive fast, e.g. putts, would otherwise stop within a hundredth of the
            # extent at rates of hundreds per second)
            v_star = float(sf(np.asarray(demos.target, dtype=float)))
            radius = max(radius, STRENGTH_STEPS * v_star * demos.estimated_dt())
        return sf, min(radius, STRENGTH_RADIUS_MAX * extent)


def _check_solver_options(settings: SEDSSettings) -> None:
    """IPOPT's verdict on ``solver_options`` (and the learner's own options), on a problem of
    one variable, before any work: a bad name or value is a :class:`SettingsError` naming it,
    not CasADi's error from inside the fit."""
    if not settings.solver_options:
        return
    x = ca.SX.sym("x")
    opts = SEDS._ipopt_options(settings, Hessian.EXACT)
    try:
        ca.nlpsol("seds_options_check", "ipopt", {"x": x, "f": x**2}, opts)(x0=1.0)
    except RuntimeError as exc:
        last = [ln for ln in str(exc).splitlines() if ln.strip()][-1]
        raise SettingsError(
            f"IPOPT refused solver_options {dict(settings.solver_options)!r}: "
            f"{last.split(': ', 1)[-1].strip()} (names and types as in IPOPT's documentation, "
            "e.g. {'mu_strategy': 'adaptive', 'max_cpu_time': 60.0})") from None


def _supports(demos: Demonstrations, settings: SEDSSettings, K: int) -> bool:
    """Whether the data support K components: at least 2 samples per component and one
    velocity value per parameter (as :func:`build_problem` asks)."""
    ps = settings.problem
    n, d = demos.n_samples, demos.n_dims
    size = Layout(K, d, with_noise=ps.with_noise, lyapunov=ps.lyapunov,
                  formulation=ps.formulation).size
    return n >= 2 * K and n * d >= size


def _best_candidate(metrics: dict, ratios: dict) -> int | None:
    """The K of the lowest score of :func:`choose_by_reproduction` so far (None: none
    scored)."""
    try:
        _, table = choose_by_reproduction(metrics, speed_ratios=ratios)
    except ValueError:
        return None
    valid = {K: v for K, v in table.items() if v is not None}
    return min(valid, key=valid.get) if valid else None


def _peak_ratios(scores: dict, demo_peaks: np.ndarray) -> np.ndarray:
    """Each reproduction's peak speed (sub-steps included) over its demonstration's."""
    return np.asarray(scores["peak_speeds"], dtype=float) / np.maximum(demo_peaks, 1e-300)


def _time_scaled(model: StableDS, c: float) -> StableDS:
    """The model with f multiplied by c > 0 (every A_k and velocity mean scaled): the same
    streamlines and the same certificate (P A_k + A_k^T P < 0 is unchanged by c > 0), run c
    times as fast."""
    d = model.n_dims
    means, covs = model.means.copy(), model.covariances.copy()
    means[:, d:] *= c
    covs[:, d:, :d] *= c
    covs[:, :d, d:] *= c
    covs[:, d:, d:] *= c * c
    info = dict(model.fit_info, time_scale=float(c),
                speed_factor=float(model.fit_info.get("speed_factor", 1.0)) * c)
    learned = model.fit_info.get("lyapunov") == "learned"
    return StableDS(model.priors, means, covs, model.target, info,
                    str(model.fit_info.get("status", "time-scaled")),
                    lyapunov=model.lyapunov_matrix if learned else None)


#: IPOPT solvers of fits without constraints whose data enter as parameters (the Gram
#: objective), with their iteration callbacks, by (symbols, options): built once per process.
#: A solver is taken out while it solves (another thread builds its own) and put back after a
#: solve that ended normally.
_SOLVERS: dict = {}
_SOLVERS_MAX = 32
_SOLVERS_LOCK = threading.Lock()


def _take_solver(key) -> tuple | None:
    """The cached (solver, progress) for ``key`` (None: none, or ``key`` is None)."""
    if key is None:
        return None
    with _SOLVERS_LOCK:
        return _SOLVERS.pop(key, None)


def _keep_solver(key, entry: tuple) -> None:
    """Put (solver, progress) in the cache under ``key`` (nothing if ``key`` is None)."""
    if key is None:
        return
    with _SOLVERS_LOCK:
        _SOLVERS[key] = entry
        while len(_SOLVERS) > _SOLVERS_MAX:
            _SOLVERS.pop(next(iter(_SOLVERS)))


def _run(solver, progress: _Progress, **inputs) -> tuple[dict, dict]:
    """One IPOPT solve, interruptible: the solver's (results, stats).

    Ctrl-C or SIGTERM while IPOPT iterates stops it at its next iteration and raises the
    signal's ``KeyboardInterrupt`` here, so no model is built from the cut-short solve. A solve
    that IPOPT ended on an exception inside CasADi (``NonIpopt_Exception_Thrown``: one of our
    callbacks raised) is a :class:`SolverError`, never a model.
    """
    with deferred_interrupts() as interrupt:
        progress.interrupt, progress.interrupted = interrupt, False
        try:
            res = solver(**inputs)
        finally:
            progress.interrupt = None
    if progress.interrupted:
        raise KeyboardInterrupt
    stats = solver.stats()
    status = str(stats.get("return_status", "unknown"))
    if status in ("NonIpopt_Exception_Thrown", "User_Requested_Stop"):
        raise SolverError("IPOPT stopped on an error raised inside it (see the messages above) "
                          f"after {stats.get('iter_count')} iterations; no model is built from "
                          "the cut-short solve", status)
    return res, stats


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
