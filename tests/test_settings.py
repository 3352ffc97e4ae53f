"""SEDS's settings (issue 27): every parameter declared the scikit-learn way and checked by fit
before any work, the combinations refused in one place, the problem built from one settings
object."""

import dataclasses
import inspect
import math
from contextlib import contextmanager
from unittest import mock

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.base import clone
from sklearn.utils._param_validation import InvalidParameterError
from sklearn.utils.estimator_checks import check_param_validation

from seds_casadi import SEDS, Demonstrations
from seds_casadi.core import seds as seds_module
from seds_casadi.core.parametrization import Layout
from seds_casadi.core.problem import build_problem
from seds_casadi.core.settings import (
    AUTO_SETTINGS,
    PARAMETER_CONSTRAINTS,
    Formulation,
    GMMMode,
    Hessian,
    Init,
    Lyapunov,
    Objective,
    ProblemSettings,
    SEDSSettings,
    SpeedCalibration,
)

#: the modes, by parameter name
MODES = {"objective": Objective, "hessian": Hessian, "lyapunov": Lyapunov,
         "formulation": Formulation, "init": Init, "gmm": GMMMode,
         "speed_calibration": SpeedCalibration}
NAN, INF = float("nan"), float("inf")

#: bad values of every parameter that has any (checked against the declaration below)
BAD = {
    "n_components": [0, -1, 2.5, True, "aic", None],
    "objective": ["speed", "MSE", 3, None],
    "random_state": ["seed", -1, 2.5],
    "omega_lower": [0.0, -1.0, NAN, INF, "1", True],
    "omega_upper": [0.0, NAN, None],
    "stability_margin": [0.0, -1e-3, NAN],
    "max_iter": [0, 2.5, True, "10", None],
    "tol": [0.0, -1.0, NAN, INF],
    "tol_objective_change": [-1e-3, NAN, INF],
    "hessian": ["bfgs", None],
    "require_convergence": [1, "yes", None],
    "compile": [0, "no"],
    "approach_direction": [3.0, "x"],
    "approach_ratio": [0.5, NAN, None],
    "lyapunov": ["quadratic"],
    "formulation": ["penalty"],
    "constraints": [[1, 2], "g >= 0"],
    "speed_calibration": ["fast"],
    "strength_components": [0, -2, 1.5, True],
    "gain_limit": [-1.0, 0.0, NAN, INF],
    "init": ["kmeans"],
    "gmm": ["frozen"],
    "solver_options": ["mu_strategy=adaptive", [("tol", 1e-8)]],
    "verbose": [-1, "yes"],
}


def _demos(d: int = 2) -> Demonstrations:
    rng = np.random.default_rng(0)
    t = np.linspace(0, 1, 30)[:, None]
    pos = [np.exp(-3 * t) * rng.uniform(0.5, 1.5, d) for _ in range(2)]
    return Demonstrations(pos, dt=1.0 / 29)


DEMOS = _demos()


@contextmanager
def no_work():
    """Fail if a fit gets as far as choosing K, fitting the strength factor, building the
    problem or solving: the settings must have been refused before."""
    def work(*args, **kwargs):
        raise AssertionError("the fit started working before refusing its settings")

    with mock.patch.object(seds_module, "build_problem", work), \
            mock.patch.object(seds_module, "bic_n_components", work), \
            mock.patch.object(seds_module.SEDS, "_fit_strength", staticmethod(work)), \
            mock.patch.object(seds_module.SEDS, "_solve", work):
        yield


def _refusal(**params) -> Exception:
    learner = SEDS(**params)  # scikit-learn convention: __init__ only stores
    assert all(learner.get_params()[k] is v for k, v in params.items())
    with no_work(), pytest.raises((ValueError, TypeError)) as info:
        learner.fit(DEMOS)
    return info.value


# ------------------------------------------------------------------ the declaration
def test_every_parameter_is_declared_and_only_n_components_is_positional():
    params = inspect.signature(SEDS).parameters
    assert set(SEDS._parameter_constraints) == set(params) == set(SEDS().get_params())
    assert SEDS._parameter_constraints is PARAMETER_CONSTRAINTS
    kinds = {name: p.kind for name, p in params.items()}
    assert kinds.pop("n_components") is inspect.Parameter.POSITIONAL_OR_KEYWORD
    assert set(kinds.values()) == {inspect.Parameter.KEYWORD_ONLY}
    with pytest.raises(TypeError, match="positional"):
        SEDS(2, "mse")
    assert set(BAD) == set(PARAMETER_CONSTRAINTS)  # the table below covers every parameter


def test_scikit_learns_own_check_of_the_declared_constraints():
    """scikit-learn's estimator check: a value of a wrong type, and a value of the right type
    out of range, for every parameter, raise InvalidParameterError naming it from fit."""
    with no_work():
        check_param_validation("SEDS", SEDS())


@pytest.mark.parametrize("name, value", [(n, v) for n, vs in BAD.items() for v in vs],
                         ids=lambda x: repr(x)[:20])
def test_a_bad_value_of_each_parameter_is_refused_by_fit_before_any_work(name, value):
    exc = _refusal(**{name: value})
    assert isinstance(exc, InvalidParameterError), repr(exc)
    assert isinstance(exc, ValueError) and isinstance(exc, TypeError)
    text = str(exc)
    assert text.startswith(f"The {name!r} parameter of SEDS must be "), text
    assert f"Got {value!r} instead" in text
    if name in MODES:  # every valid name, in the mode's order, then "auto" if it has one
        listed = ", ".join(repr(v) for v in MODES[name].values())
        auto = ", 'auto'" if name in AUTO_SETTINGS else ""
        assert f"a str among {{{listed}{auto}}}" in text, text


@pytest.mark.parametrize("value", [[0.0, 0.0], [NAN, 1.0], [[INF, 1.0]]])
def test_an_approach_direction_that_is_no_direction_is_refused_before_any_work(value):
    exc = _refusal(approach_direction=value)
    assert type(exc) is ValueError and "approach_direction must be a finite non-zero" in str(exc)


@pytest.mark.parametrize("options", [{1: 2}, {"tol": None}, {"tol": True}, {"tol": [1e-8]}])
def test_solver_options_contents_are_checked_before_any_work(options):
    exc = _refusal(solver_options=options)
    assert isinstance(exc, TypeError) and "solver_options" in str(exc)


@settings(max_examples=60, derandomize=True, deadline=None, database=None)
@given(name=st.sampled_from(sorted(MODES)), value=st.text(max_size=20))
def test_any_unknown_mode_name_is_refused_with_the_valid_names(name, value):
    if value in MODES[name].values():
        return
    text = str(_refusal(**{name: value}))
    assert f"The {name!r} parameter of SEDS" in text
    assert all(repr(v) in text for v in MODES[name].values())


_POSITIVE = ("omega_lower", "omega_upper", "stability_margin", "tol", "gain_limit")


@settings(max_examples=60, derandomize=True, deadline=None, database=None)
@given(name=st.sampled_from(_POSITIVE + ("tol_objective_change", "approach_ratio")),
       value=st.one_of(st.floats(max_value=0.0), st.floats(-1e300, 0.999),
                       st.sampled_from([NAN, INF, -INF])))
def test_numbers_out_of_their_range_are_refused(name, value):
    low_ok = {"tol_objective_change": 0.0, "approach_ratio": 1.0}.get(name)
    if math.isfinite(value) and (value > 0 if low_ok is None else value >= low_ok):
        return  # inside the range: not a bad value
    assert f"The {name!r} parameter of SEDS" in str(_refusal(**{name: value}))


@settings(max_examples=40, derandomize=True, deadline=None, database=None)
@given(name=st.sampled_from(["n_components", "max_iter", "strength_components"]),
       value=st.one_of(st.integers(max_value=0), st.floats(allow_nan=True), st.booleans()))
def test_counts_must_be_positive_integers(name, value):
    assert f"The {name!r} parameter of SEDS" in str(_refusal(**{name: value}))


def test_modes_are_given_by_name_or_by_member():
    assert Objective.MSE == "mse" and Hessian.values() == ("auto", "exact", "limited-memory")
    learner = SEDS(2, objective=Objective.MSE, lyapunov=Lyapunov.LEARNED)
    assert clone(learner).get_params()["objective"] is Objective.MSE
    s = SEDSSettings.from_params(learner.get_params())
    assert s.problem.objective is Objective.MSE and s.problem.lyapunov is Lyapunov.LEARNED
    with pytest.raises(ValueError, match="unknown lyapunov 'quadratic'; valid: identity, learned"):
        Layout(2, 2, with_noise=False, lyapunov="quadratic")


# ------------------------------------------------------------------ combinations
@pytest.mark.parametrize("name", ["hessian_approximation", "ipopt.hessian_approximation"])
@pytest.mark.parametrize("hessian", ["limited-memory", "exact", "auto"])
def test_a_hessian_set_in_solver_options_is_refused_before_any_work(name, hessian):
    # hessian decides whether the Hessian kernels are built: with "limited-memory" in the
    # settings and "exact" in the options, IPOPT used to fail inside its first iteration
    exc = _refusal(hessian=hessian, solver_options={name: "exact"})
    assert type(exc) is ValueError
    assert "'hessian_approximation'" in str(exc) and "use hessian='exact' or " in str(exc)


def test_an_approach_direction_of_another_dimension_is_refused_before_any_work():
    exc = _refusal(approach_direction=[1.0, 0.0, 0.0])
    assert type(exc) is ValueError
    assert str(exc) == "approach_direction has 3 entries for 2-D demonstrations"


def test_settings_resolve_what_a_combination_means():
    default = SEDSSettings.from_params(SEDS(objective="direction").get_params())
    assert default.speed_calibration is SpeedCalibration.STRENGTH and default.fits_strength
    for objective in ("mse", "likelihood"):  # they fit speeds: no calibration, no strength
        s = SEDSSettings.from_params(SEDS(objective=objective,
                                          speed_calibration="median").get_params())
        assert s.speed_calibration is None and not s.fits_strength
    assert SEDSSettings.from_params(SEDS("bic").get_params()).problem.n_components is None
    # SEDS(): the automatic settings (issue 29) and K to be chosen among 4, 7, 10
    auto = SEDSSettings.from_params(SEDS().get_params())
    assert auto.speed_calibration is None and auto.problem.gram_statistics
    assert auto.k_candidates == (4, 7, 10)
    s = SEDSSettings.from_params(SEDS(objective="direction", approach_direction=[3.0, 4.0],
                                      tol_objective_change=0).get_params())
    np.testing.assert_allclose(s.approach_direction, [0.6, 0.8])
    assert s.ipopt_objective_change_tol == 1e20  # 0 disables the early stop
    gram = {(o, g, f): ProblemSettings(2, objective=o, gmm=g, formulation=f).gram_statistics
            for o in Objective for g in GMMMode for f in Formulation}
    assert [k for k, v in gram.items() if v] == [
        (Objective.MSE, GMMMode.FIXED, Formulation.BY_CONSTRUCTION)]


# ------------------------------------------------------------------ the problem's settings
def test_build_problem_takes_one_settings_object():
    ps = ProblemSettings(2, objective="mse", random_state=0, compile=False, init="lpv")
    assert ps.objective is Objective.MSE and ps.init is Init.LPV  # names become members
    prob = build_problem(DEMOS, ps)
    assert prob.settings is ps and prob.objective is Objective.MSE
    assert prob.hessian is Hessian.EXACT and prob.layout.K == 2
    ref = SEDS(2, objective="mse", random_state=0, compile=False, init="lpv").build_problem(DEMOS)
    assert ref.settings == ps
    np.testing.assert_array_equal(prob.theta0, ref.theta0)
    assert prob.kernels.value(prob.theta0) == ref.kernels.value(ref.theta0)
    with pytest.raises(TypeError):
        build_problem(DEMOS, 2, "mse")  # the 13 positional arguments are gone
    with pytest.raises(TypeError, match="ProblemSettings"):
        build_problem(DEMOS, {"n_components": 2})
    with pytest.raises(ValueError, match="choose K first"):
        build_problem(DEMOS, ProblemSettings(None))
    with pytest.raises(dataclasses.FrozenInstanceError):
        ps.objective = Objective.DIRECTION


@pytest.mark.parametrize("field, value", [("n_components", 0), ("objective", "speed"),
                                          ("gain_limit", -1.0), ("compile", "yes")])
def test_problem_settings_refuse_bad_values_naming_them(field, value):
    kwargs = {"n_components": 2, field: value}
    with pytest.raises(InvalidParameterError,
                       match=f"The '{field}' parameter of ProblemSettings must be"):
        ProblemSettings(**kwargs)


def test_fit_info_records_the_settings_as_plain_strings():
    info = SEDS(1, objective="mse", random_state=0, compile=False,
                max_iter=30).fit(DEMOS).model_.fit_info
    for key, value in (("objective_name", "mse"), ("lyapunov", "identity"),
                       ("formulation", "by-construction"), ("init", "joint-em"),
                       ("gmm", "joint"), ("hessian", "exact")):
        assert type(info[key]) is str and info[key] == value
    assert info["speed_calibration"] is None
