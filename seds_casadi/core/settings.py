"""SEDS's settings: the modes and their allowed values, the declared parameter constraints, the
checks of settings that do not go together, and the frozen settings a problem is built from.

Every mode of :class:`~seds_casadi.core.seds.SEDS` given by name (``objective="mse"``,
``lyapunov="learned"``, ...) is a :class:`Mode` (a :class:`enum.StrEnum`) declared here once:

* :data:`PARAMETER_CONSTRAINTS`, scikit-learn's declaration of every parameter's allowed types and
  values (``SEDS._parameter_constraints``), is built from them; ``SEDS.fit`` checks its
  parameters against it before any work, and a bad value raises scikit-learn's
  ``InvalidParameterError`` (a ``ValueError`` and a ``TypeError``) naming the parameter and what
  it accepts;
* :class:`ProblemSettings` (what :func:`~seds_casadi.core.problem.build_problem` takes) and
  :class:`SEDSSettings` (everything a fit uses) hold the modes as members, so that the rest of
  ``core/`` compares members (``settings.objective is Objective.MSE``: a misspelt member is an
  ``AttributeError`` where a misspelt string would be a silent ``False``) and asks the settings
  what a combination means (:attr:`ProblemSettings.gram_statistics`,
  :attr:`SEDSSettings.fits_strength`) instead of repeating it;
* settings that are valid one by one but not together are refused in one place,
  :meth:`SEDSSettings.from_params`, before any work.

A member equals its name (``Objective.MSE == "mse"``), so users keep passing plain strings.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from enum import StrEnum
from numbers import Integral, Real
from types import MappingProxyType
from typing import Any

import numpy as np
from sklearn.utils._param_validation import Interval, StrOptions, validate_parameter_constraints

__all__ = ["Mode", "Objective", "Lyapunov", "Formulation", "Init", "GMMMode", "Hessian",
           "SpeedCalibration", "OBJECTIVES", "PARAMETER_CONSTRAINTS", "ProblemSettings",
           "SEDSSettings", "NumberRange", "ModeOptions", "AUTO", "AUTO_SETTINGS", "BEST_SETTINGS",
           "CLASSIC_SETTINGS", "AUTO_K_RANGE", "AUTO_K_STEP", "AUTO_K_CANDIDATES", "MAX_ITER",
           "MIN_GAIN_LIMIT", "MAX_STABILITY_MARGIN", "SettingsError"]


class Mode(StrEnum):
    """A setting chosen by name; each member equals its name (``Objective.MSE == "mse"``)."""

    @classmethod
    def values(cls) -> tuple[str, ...]:
        """The names, in declaration order (the default first): for command-line choices."""
        return tuple(m.value for m in cls)

    @classmethod
    def parse(cls, value, name: str):
        """``value`` (a name or a member) as a member; a ``ValueError`` naming the parameter
        ``name`` and the valid names otherwise."""
        try:
            return cls(value)
        except ValueError:
            raise ValueError(f"unknown {name} {value!r}; valid: "
                             f"{', '.join(cls.values())}") from None


class Objective(Mode):
    """``objective``: what IPOPT minimises (:func:`~seds_casadi.core.objectives.sample_objective`)."""

    DIRECTION = "direction"    # Eq. 9: weighted cosine between demonstrated and model velocities
    MSE = "mse"                # mean squared velocity error (original SEDS)
    LIKELIHOOD = "likelihood"  # negative log-likelihood of the joint GMM (original SEDS)


class Lyapunov(Mode):
    """``lyapunov``: V(x) = |x - x*|^2 (SEDS) or (x - x*)^T P (x - x*) with P learned."""

    IDENTITY = "identity"
    LEARNED = "learned"


class Formulation(Mode):
    """``formulation``: Eq. 10 by the parametrization, or as constraints of the NLP."""

    BY_CONSTRUCTION = "by-construction"
    CONSTRAINED = "constrained"


class Init(Mode):
    """``init``: IPOPT's starting point (see ``SEDS``'s docstring)."""

    JOINT_EM = "joint-em"  # k-means + EM on [x; xdot] (SEDS)
    LPV = "lpv"            # EM on x, least-squares stable gains (LPV-DS)
    PC = "pc"              # as LPV, from a physically-consistent clustering (PC-GMM)


class GMMMode(Mode):
    """``gmm``: IPOPT optimises the GMM and the dynamics (SEDS), or the dynamics only."""

    JOINT = "joint"
    FIXED = "fixed"


class Hessian(Mode):
    """``hessian``: exact second derivatives, IPOPT's L-BFGS, or chosen by problem size."""

    AUTO = "auto"
    EXACT = "exact"
    LIMITED_MEMORY = "limited-memory"


class SpeedCalibration(Mode):
    """``speed_calibration``: how a direction-objective model gets the demonstrated speeds."""

    STRENGTH = "strength"            # a strength factor v(x) by GMR (Eq. 12)
    MEDIAN = "median"                # one factor on every A_k: median speed ratio 1
    LEAST_SQUARES = "least-squares"  # one factor on every A_k, least squares


#: the objective names, in order (command-line choices, test grids)
OBJECTIVES = Objective.values()


# ------------------------------------------------------------------ the declared constraints
class NumberRange(Interval):
    """scikit-learn's ``Interval``, refusing booleans (``n_components=True`` or ``tol=False``
    is a mistake, not the number 1 or 0)."""

    def is_satisfied_by(self, val) -> bool:
        return not isinstance(val, bool | np.bool_) and super().is_satisfied_by(val)


class ModeOptions(StrOptions):
    """scikit-learn's ``StrOptions`` of a :class:`Mode`'s names, listed in the mode's order."""

    def __init__(self, mode: type[Mode], extra: tuple[str, ...] = ()) -> None:
        super().__init__(set(mode.values()) | set(extra))
        self.mode, self.extra = mode, tuple(extra)

    def __str__(self) -> str:
        return "a str among {" + ", ".join(repr(v) for v in self.mode.values() + self.extra) + "}"


_POSITIVE = NumberRange(Real, 0, None, closed="neither")  # finite and > 0 (inf, nan refused)
_COUNT = NumberRange(Integral, 1, None, closed="left")


class SettingsError(ValueError):
    """Settings that are valid one by one but make no sense together, or for the data (a K
    range the demonstrations cannot support): raised before any solve."""


#: the value of a setting the learner chooses itself (``SEDS()``'s default)
AUTO = "auto"
#: the settings chosen automatically (``"auto"``)
AUTO_SETTINGS = ("objective", "lyapunov", "init", "gmm", "gain_limit")
#: what the ``"auto"`` settings become with the squared-error objective (the default): a
#: physically-consistent GMM kept fixed, a learned P and a gain limit. On the ds-opt LASA
#: protocol this was the best of the learner's variants (``benchmarks/README.md``, issues 13,
#: 14, 29), and its fits take a fraction of a second (the Gram statistics), so that several K
#: can be tried
BEST_SETTINGS = MappingProxyType({"objective": "mse", "init": "pc", "gmm": "fixed",
                                  "lyapunov": "learned", "gain_limit": 10.0})
#: ... and with settings the above was not measured with (another objective, the constrained
#: formulation, an arrival constraint or constraints of the user's own): SEDS's own
CLASSIC_SETTINGS = MappingProxyType({"objective": "direction", "init": "joint-em",
                                     "gmm": "joint", "lyapunov": "identity", "gain_limit": None})
#: the range of K searched by ``n_components="auto"`` (limited to what the data supports) ...
AUTO_K_RANGE = (4, 10)
#: ... first every AUTO_K_STEP-th K of it, 4, 7 and 10, then the neighbours K - 1 and K + 1
#: of the best-scoring K until the best one's neighbours are all tried (``SEDS._fit_candidates``):
#: the grid finds the region, the neighbours its best K. On the ds-opt LASA protocol this gave
#: test means of 4.84 / 0.058 / 1,430 (RMSE / e_dot / DTWD) in a median 0.31 s a shape against
#: 4.84 / 0.058 / 1,433 in 0.48 s for every K of 4-10 (one core; benchmarks/README.md, issue
#: 29); the grid alone was faster (0.22 s) but on a 3-D helix it missed the best K by 37 % of
#: the score and one reproduction peaked at 0.75x the demonstration's speed
AUTO_K_STEP = 3
#: the K ``n_components="auto"`` tries first
AUTO_K_CANDIDATES = tuple(range(AUTO_K_RANGE[0], AUTO_K_RANGE[1] + 1, AUTO_K_STEP))
#: K taken by ``n_components="auto"`` when the settings are not :data:`BEST_SETTINGS` (their
#: fits are too slow to try several K by default; the default K before issue 29)
CLASSIC_K = 5
#: largest ``max_iter`` (IPOPT reads it as a 32-bit integer; a million iterations of a SEDS
#: problem is already days)
MAX_ITER = 10**6
#: smallest ``gain_limit`` (the gains' bounds in the scaled frame, where the data's own rate is
#: about 1: below this no component could follow the data, and IPOPT's bounds collapse)
MIN_GAIN_LIMIT = 1e-3
#: largest ``stability_margin`` (m in A_k + A_k^T <= -2 m I, scaled frame: a margin of 10 asks
#: every component to contract 10 times faster than the data move)
MAX_STABILITY_MARGIN = 10.0


class _KOptions(StrOptions):
    """``n_components``' names, listed in a fixed order."""

    def __init__(self) -> None:
        super().__init__({AUTO, "bic"})

    def __str__(self) -> str:
        return "a str among {'auto', 'bic'}"


class _KCandidates(Interval):
    """``n_components`` given as the K to try: a sequence of positive integers."""

    def __init__(self) -> None:
        super().__init__(Integral, 1, None, closed="left")

    def is_satisfied_by(self, val) -> bool:
        if isinstance(val, str | bytes | dict) or not hasattr(val, "__len__"):
            return False
        try:
            items = list(val)
        except TypeError:
            return False
        return len(items) > 0 and all(
            isinstance(k, Integral) and not isinstance(k, bool | np.bool_) for k in items)

    def __str__(self) -> str:
        return "a sequence of positive ints (the K to try, e.g. range(4, 11))"

#: every SEDS parameter's allowed types and values, as scikit-learn declares them
#: (``SEDS._parameter_constraints``; checked by ``SEDS.fit`` before any work)
PARAMETER_CONSTRAINTS: dict[str, list] = {
    "n_components": [_COUNT, _KOptions(), _KCandidates()],
    "objective": [ModeOptions(Objective, (AUTO,))],
    "random_state": ["random_state", np.random.Generator],
    "omega_lower": [_POSITIVE],
    "omega_upper": [_POSITIVE],
    "stability_margin": [NumberRange(Real, 0, MAX_STABILITY_MARGIN, closed="right")],
    "max_iter": [NumberRange(Integral, 1, MAX_ITER, closed="both")],
    "tol": [_POSITIVE],
    "tol_objective_change": [NumberRange(Real, 0, None, closed="left")],
    "hessian": [ModeOptions(Hessian)],
    "require_convergence": ["boolean"],
    "compile": ["boolean"],
    "approach_direction": ["array-like", None],
    "approach_ratio": [NumberRange(Real, 1, None, closed="left")],
    "lyapunov": [ModeOptions(Lyapunov, (AUTO,))],
    "formulation": [ModeOptions(Formulation)],
    "constraints": [callable, None],
    "speed_calibration": [ModeOptions(SpeedCalibration)],
    "strength_components": [_COUNT, None],
    "gain_limit": [NumberRange(Real, MIN_GAIN_LIMIT, None, closed="left"), None,
                   StrOptions({AUTO})],
    "init": [ModeOptions(Init, (AUTO,))],
    "gmm": [ModeOptions(GMMMode, (AUTO,))],
    "solver_options": [dict, None],
    "verbose": ["verbose"],
}

#: the modes among the settings of a problem, by parameter name
_PROBLEM_MODES: dict[str, type[Mode]] = {
    "objective": Objective, "hessian": Hessian, "lyapunov": Lyapunov,
    "formulation": Formulation, "init": Init, "gmm": GMMMode,
}
#: IPOPT options that the learner's own settings decide (refused in ``solver_options``)
_OWN_IPOPT_OPTIONS = {
    "hessian_approximation": "hessian='exact' or 'limited-memory' (the problem's Hessian "
                             "kernels are built, or not, for it)",
}


# ------------------------------------------------------------------ the settings of a problem
@dataclass(frozen=True)
class ProblemSettings:
    """The settings a SEDS problem is built from (:func:`~seds_casadi.core.problem.build_problem`).

    The fields are the :class:`~seds_casadi.core.seds.SEDS` parameters of the same names, checked
    against :data:`PARAMETER_CONSTRAINTS` on construction (a bad value raises scikit-learn's
    ``InvalidParameterError``, a ``ValueError``); the modes are stored as :class:`Mode` members
    (names are converted).

    Parameters
    ----------
    n_components : int or None
        K; None when not chosen yet (``SEDS(n_components="bic")`` chooses it on the data before
        the problem is built; :func:`build_problem` refuses None).
    objective, hessian, lyapunov, formulation, init, gmm : Mode or str
    omega_lower, omega_upper, stability_margin : float
    random_state : int, numpy Generator, RandomState or None
    compile : bool
    gain_limit : float or None
    """

    n_components: int | None
    objective: Objective = Objective.DIRECTION
    omega_lower: float = 1.0
    omega_upper: float = 2.0
    stability_margin: float = 1e-3
    random_state: Any = None
    compile: bool = True
    hessian: Hessian = Hessian.AUTO
    lyapunov: Lyapunov = Lyapunov.IDENTITY
    formulation: Formulation = Formulation.BY_CONSTRUCTION
    gain_limit: float | None = None
    init: Init = Init.JOINT_EM
    gmm: GMMMode = GMMMode.JOINT

    def __post_init__(self) -> None:
        values = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        constraints = {name: PARAMETER_CONSTRAINTS[name] for name in values}
        constraints["n_components"] = [_COUNT, None]
        validate_parameter_constraints(constraints, values, caller_name=type(self).__name__)
        for name, mode in _PROBLEM_MODES.items():
            object.__setattr__(self, name, mode(values[name]))
        if self.n_components is not None:
            object.__setattr__(self, "n_components", int(self.n_components))

    @property
    def with_noise(self) -> bool:
        """The optimisation vector holds the noise covariances Q_k (the likelihood objective)."""
        return self.objective is Objective.LIKELIHOOD

    @property
    def constrained(self) -> bool:
        """Eq. 10 as NLP constraints (the paper's form), not by the parametrization."""
        return self.formulation is Formulation.CONSTRAINED

    @property
    def learned_lyapunov(self) -> bool:
        """P of V(x) = (x - x*)^T P (x - x*) is optimised (P = I otherwise)."""
        return self.lyapunov is Lyapunov.LEARNED

    @property
    def fixed_gmm(self) -> bool:
        """The priors, means and Sigma_x keep the values of the initialisation."""
        return self.gmm is GMMMode.FIXED

    @property
    def gram_statistics(self) -> bool:
        """The objective is a quadratic form in the gains with (K d)-square statistics
        (:class:`~seds_casadi.core.objectives.GramKernels`): the mixing is fixed, the objective
        is the squared error, and the gains are the by-construction form's."""
        return self.fixed_gmm and self.objective is Objective.MSE and not self.constrained


# ------------------------------------------------------------------ the settings of a fit
@dataclass(frozen=True, eq=False)
class SEDSSettings:
    """Everything a SEDS fit uses: the problem's settings and the solve's, checked together.

    Built by :meth:`from_params` from a learner's parameters (``SEDS.get_params()``).

    Attributes
    ----------
    problem : ProblemSettings
    speed_calibration : SpeedCalibration or None
        None unless the objective is ``"direction"`` (the other objectives fit the speeds).
    strength_components : int or None
    approach_direction : array, shape (d,), or None
        A unit vector.
    approach_ratio : float
    constraints : callable or None
    max_iter : int
    tol, tol_objective_change : float
    require_convergence, verbose : bool
    solver_options : mapping
        Read-only; IPOPT's names as the user gave them.
    k_candidates : tuple of int or None
        The K to try (``n_components="auto"`` or a sequence), smallest first; None when K is
        given or chosen by BIC.
    choice : mapping
        For each setting of :data:`AUTO_SETTINGS` and ``n_components``: ``"given"`` or why the
        learner set it (``fit_info["choice"]``).
    """

    problem: ProblemSettings
    speed_calibration: SpeedCalibration | None
    strength_components: int | None
    approach_direction: np.ndarray | None
    approach_ratio: float
    constraints: Callable | None
    max_iter: int
    tol: float
    tol_objective_change: float
    require_convergence: bool
    solver_options: Mapping[str, Any]
    verbose: bool
    k_candidates: tuple[int, ...] | None = None
    choice: Mapping[str, str] = dataclasses.field(default_factory=dict)

    @classmethod
    def from_params(cls, params: Mapping[str, Any], n_dims: int | None = None) -> SEDSSettings:
        """The settings of SEDS parameters already checked against
        :data:`PARAMETER_CONSTRAINTS` (``SEDS._validate_params``): the modes as members, the
        values no declaration can check (``approach_direction``, the ``solver_options``'
        contents) checked, and the combinations refused here and nowhere else, before any work.

        Parameters
        ----------
        params : mapping
            ``SEDS.get_params()``.
        n_dims : int, optional
            The demonstrations' dimension, to check the settings against (when known).

        Raises
        ------
        ValueError, TypeError
            With what to change.
        """
        params, choice = resolve_auto(params)
        K = params["n_components"]
        candidates = None
        if isinstance(K, str) and K == AUTO:
            fast = (params["gmm"] == GMMMode.FIXED and params["objective"] == Objective.MSE
                    and params["formulation"] == Formulation.BY_CONSTRUCTION)
            if fast:
                candidates = AUTO_K_CANDIDATES
                choice["n_components"] = (
                    f"auto: the K whose reproductions of the demonstrations fit them best "
                    f"(model_selection.choose_by_reproduction) among {', '.join(map(str, candidates))} "
                    f"({AUTO_K_RANGE[0]}-{AUTO_K_RANGE[1]} in steps of {AUTO_K_STEP}) and the "
                    "neighbours of the best")
            else:
                K = CLASSIC_K
                choice["n_components"] = (
                    f"auto: {CLASSIC_K}, the classic default (K is searched only when each fit "
                    "is fast: gmm='fixed' with objective='mse')")
        elif isinstance(K, str):
            choice["n_components"] = "bic"
        elif not isinstance(K, Integral):
            candidates = _k_candidates(K)
            choice["n_components"] = "given: the K tried " + ", ".join(map(str, candidates))
        else:
            choice["n_components"] = "given"
        problem = ProblemSettings(
            n_components=None if (isinstance(K, str) or candidates is not None) else K,
            **{name: params[name] for name in (f.name for f in dataclasses.fields(ProblemSettings))
               if name != "n_components"})
        u = params["approach_direction"]
        if u is not None:
            u = np.asarray(u, dtype=float).ravel()
            if not (np.all(np.isfinite(u)) and np.linalg.norm(u) > 0):
                raise ValueError("approach_direction must be a finite non-zero vector")
            u = u / np.linalg.norm(u)
            u.setflags(write=False)
        sk = params["strength_components"]
        settings = cls(
            problem=problem,
            speed_calibration=(SpeedCalibration(params["speed_calibration"])
                               if problem.objective is Objective.DIRECTION else None),
            strength_components=None if sk is None else int(sk),
            approach_direction=u, approach_ratio=float(params["approach_ratio"]),
            constraints=params["constraints"], max_iter=int(params["max_iter"]),
            tol=float(params["tol"]), tol_objective_change=float(params["tol_objective_change"]),
            require_convergence=bool(params["require_convergence"]),
            solver_options=MappingProxyType(_solver_options(params["solver_options"])),
            verbose=bool(params["verbose"]), k_candidates=candidates,
            choice=MappingProxyType(choice))
        settings._check_combinations(n_dims)
        return settings

    def _check_combinations(self, n_dims: int | None) -> None:
        """The one place where settings valid one by one are refused together."""
        for name in self.solver_options:
            bare = name.removeprefix("ipopt.")
            if bare in _OWN_IPOPT_OPTIONS:
                raise ValueError(f"solver_options sets {bare!r}, which the learner's own "
                                 f"settings decide: use {_OWN_IPOPT_OPTIONS[bare]} instead")
        ps = self.problem
        if ps.gain_limit is not None and ps.stability_margin >= ps.gain_limit:
            raise SettingsError(
                f"stability_margin={ps.stability_margin:g} is not below gain_limit="
                f"{ps.gain_limit:g}: every component must contract at least at the margin's rate "
                "and at most at about the gain limit's; lower the margin or raise the limit")
        if ps.fixed_gmm and ps.constrained:
            raise SettingsError("gmm='fixed' optimises the gains of the by-construction form; "
                                "use formulation='by-construction' with it, or gmm='joint'")
        u = self.approach_direction
        if u is not None and n_dims is not None and u.shape != (n_dims,):
            raise ValueError(f"approach_direction has {u.shape[0]} entries for {n_dims}-D "
                             "demonstrations")

    def with_components(self, n_components: int) -> SEDSSettings:
        """The same settings with K chosen (``n_components="bic"``)."""
        return dataclasses.replace(
            self, problem=dataclasses.replace(self.problem, n_components=n_components))

    @property
    def fits_strength(self) -> bool:
        """A strength factor v(x) is learned (the direction objective's default calibration)."""
        return self.speed_calibration is SpeedCalibration.STRENGTH

    @property
    def ipopt_objective_change_tol(self) -> float:
        """IPOPT's ``acceptable_obj_change_tol`` (``tol_objective_change``; 0 disables it)."""
        return self.tol_objective_change if self.tol_objective_change > 0 else 1e20


def resolve_auto(params: Mapping[str, Any]) -> tuple[dict, dict]:
    """The parameters with every ``"auto"`` setting of :data:`AUTO_SETTINGS` replaced, and why.

    The rule (issue 29): the automatic settings are :data:`BEST_SETTINGS` (squared velocity
    error, a physically-consistent GMM kept fixed, a learned P, ``gain_limit=10``), measured
    the best on the ds-opt LASA protocol and checked on 3-D and 7-D motions
    (``benchmarks/README.md``); ``lyapunov``, ``init``, ``gmm`` or ``gain_limit`` given
    explicitly overrides its own entry only. Naming the objective (any, ``"mse"`` included)
    asks for SEDS as published, and so does fixing something the set was not measured with
    (the constrained formulation, an arrival constraint, constraints of one's own): the
    remaining automatic settings are then SEDS's own (:data:`CLASSIC_SETTINGS`), as before
    issue 29, so that code written for those defaults fits the same model.

    Returns
    -------
    params : dict
        A copy with the choices made (``n_components`` untouched).
    choice : dict
        Per setting of :data:`AUTO_SETTINGS`: ``"given"`` or ``"auto: ..."``.
    """
    out = dict(params)
    given = {k: out[k] for k in AUTO_SETTINGS if not (isinstance(out[k], str) and out[k] == AUTO)}
    classic_reasons = []
    if "objective" in given:
        classic_reasons.append(f"objective={given['objective']!r}")
    if out.get("formulation") == Formulation.CONSTRAINED:
        classic_reasons.append("formulation='constrained'")
    if out.get("approach_direction") is not None:
        classic_reasons.append("an approach_direction")
    if out.get("constraints") is not None:
        classic_reasons.append("constraints")
    table = CLASSIC_SETTINGS if classic_reasons else BEST_SETTINGS
    why = ("auto: SEDS's own, as " + " and ".join(classic_reasons) + " was given"
           if classic_reasons else "auto: the measured best (BEST_SETTINGS)")
    choice = {}
    for k in AUTO_SETTINGS:
        if k in given:
            choice[k] = "given"
        else:
            out[k] = table[k]
            choice[k] = why
    return out, choice


def _k_candidates(value) -> tuple[int, ...]:
    """The K to try, as given in ``n_components`` (a sequence of positive ints), checked."""
    items = [int(k) for k in value]
    if any(k < 1 for k in items):
        raise SettingsError(f"n_components lists K = {min(items)}: every K must be at least 1")
    if len(set(items)) != len(items):
        raise SettingsError(f"n_components lists a K twice: {items}")
    if len(items) > 20:
        raise SettingsError(f"n_components lists {len(items)} values of K; at most 20 are "
                            "tried (each is a fit)")
    return tuple(sorted(items))


def _solver_options(options: dict | None) -> dict:
    """A copy of ``solver_options`` whose names are strings and values strings or numbers."""
    options = {} if options is None else options
    if not all(isinstance(k, str) for k in options):
        raise TypeError("solver_options must be a dict of IPOPT option names to values, "
                        f"got {options!r}")
    bad = [k for k, v in options.items()
           if isinstance(v, bool) or not isinstance(v, str | int | float | np.integer | np.floating)]
    if bad:
        raise TypeError(f"solver_options values must be strings or numbers; not those of {bad}")
    return dict(options)
