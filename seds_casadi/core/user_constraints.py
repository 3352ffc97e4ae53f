"""Constraints of the user's own on a SEDS model (``SEDS(constraints=...)``, issue 14).

The user writes constraints on the model in their own units: a callable receives a dict of
CasADi SX symbols (``priors``, ``mu_x``, ``A``, ``Sigma_x``, ``P``, ``target``) and returns
``(g, lower, upper)`` triples. :class:`UserConstraints` turns them into a Function of those model
quantities, substitutes the parametrization (scaled attractor frame back to the caller's units:
x = sx x_s + x*, A = (sv / sx) A_s, Sigma_x = sx^2 Sigma_s) to make NLP constraints of theta, and
evaluates the same Function on the returned model to check that they hold.
"""

from __future__ import annotations

from collections.abc import Callable

import casadi as ca
import numpy as np

from .errors import SolverError
from .parametrization import unpack_casadi
from .settings import Objective

#: largest violation of a user constraint accepted on the returned model (absolute, user units)
TOLERANCE = 1e-6


class UserConstraints:
    """The user's constraints for one problem: as NLP constraints, and as a check of a model.

    Parameters
    ----------
    fn : callable
        ``fn(model) -> iterable of (g, lower, upper)``.
    prob : SEDSProblem
        The problem (its layout, scales and target).
    """

    def __init__(self, fn: Callable, prob) -> None:
        K, d = prob.layout.K, prob.layout.d
        self._prob = prob
        syms = {"priors": ca.SX.sym("priors", K),
                "mu_x": [ca.SX.sym(f"mu_x{k}", d) for k in range(K)],
                "A": [ca.SX.sym(f"A{k}", d, d) for k in range(K)],
                "Sigma_x": [ca.SX.sym(f"Sigma_x{k}", d, d) for k in range(K)],
                "P": ca.SX.sym("P", d, d)}
        model = dict(syms, target=prob.target.copy())
        try:
            triples = list(fn(model))
        except Exception as exc:  # noqa: BLE001 - the user's code: say where it failed
            raise ValueError(f"the constraints callable failed on the model symbols: "
                             f"{type(exc).__name__}: {exc}") from exc
        exprs, lower, upper = [], [], []
        for n, item in enumerate(triples):
            if not (isinstance(item, tuple | list) and len(item) == 3):
                raise ValueError(f"constraint {n}: expected a (g, lower, upper) triple, got "
                                 f"{type(item).__name__}")
            g, lo, hi = item
            g = ca.vec(ca.SX(g))
            m = g.numel()
            lo = np.broadcast_to(np.asarray(lo, dtype=float), (m,)).copy()
            hi = np.broadcast_to(np.asarray(hi, dtype=float), (m,)).copy()
            if np.any(np.isnan(lo)) or np.any(np.isnan(hi)) or np.any(lo > hi):
                raise ValueError(f"constraint {n}: bounds must be numbers with lower <= upper")
            exprs.append(g)
            lower.append(lo)
            upper.append(hi)
        if not exprs:
            raise ValueError("the constraints callable returned no constraint")
        self._inputs = [syms["priors"], *syms["mu_x"], *syms["A"], *syms["Sigma_x"], syms["P"]]
        self.function = ca.Function("seds_user_constraints", self._inputs, [ca.vertcat(*exprs)])
        self.lower, self.upper = np.concatenate(lower), np.concatenate(upper)

    def _theta_model(self, theta) -> list:
        prob = self._prob
        layout, sx, sv = prob.layout, prob.position_scale, prob.velocity_scale
        th = ca.SX.sym("theta", layout.size)
        p = unpack_casadi(th, layout, prob.margin)
        pri = ca.exp(ca.vertcat(*p["logpi"]))
        if layout.constrained:
            pri = pri / ca.sum1(pri)
        mu = [m * sx + ca.DM(prob.target) for m in p["mu"]]
        A = [a * (sv / sx) for a in p["A"]]
        S = [(L @ L.T) * sx**2 for L in p["L"]]
        P = p["P"] if p["P"] is not None else ca.SX.eye(layout.d)
        f = ca.Function("model_of_theta", [th], [pri, *mu, *A, *S, P])
        return f(theta)

    def of_theta(self, theta_sym) -> ca.MX:
        """The constraint values as an expression of the optimisation vector."""
        return self.function(*self._theta_model(theta_sym))

    def check(self, model, status: str = "unknown") -> float:
        """Largest violation on a fitted :class:`StableDS`; raise above :data:`TOLERANCE`."""
        d = model.n_dims
        args = [model.priors, *model.means[:, :d], *model.A,
                *model.covariances[:, :d, :d], model.lyapunov_matrix]
        g = np.asarray(self.function(*args)).ravel()
        viol = float(np.max(np.r_[0.0, self.lower - g, g - self.upper]))
        if viol > TOLERANCE:
            worst = int(np.argmax(np.maximum(self.lower - g, g - self.upper)))
            hint = ("; with the direction objective the gains are rescaled after the solve: use "
                    "objective='mse' for constraints on them"
                    if self._prob.objective is Objective.DIRECTION else "")
            raise SolverError(
                f"the fitted model violates user constraint entry {worst} by {viol:.3g} "
                f"(value {g[worst]:.6g}, bounds [{self.lower[worst]:g}, {self.upper[worst]:g}])"
                + hint, status)
        return viol
