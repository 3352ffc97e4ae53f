"""How the SEDS parameters are laid out in the optimisation vector, and the numpy side of it.

The constraints of Eq. 10 are satisfied *by construction* (the issue lets us choose; we choose
this because it makes every IPOPT iterate a stable model and the problem smooth):

* (d), (e) priors: ``pi = softmax(l)`` with the last logit fixed to 0 (so pi_k in (0, 1), sum 1);
* (c) ``Sigma_x^k = L_k L_k^T`` with ``L_k`` lower triangular and ``diag(L_k) = exp(.)`` > 0;
* (b) ``A_k = Sigma_xdotx^k (Sigma_x^k)^-1 = -(B_k B_k^T + m I) + (W_k - W_k^T)``, with ``B_k`` lower
  triangular (positive diagonal), ``W_k`` strictly lower triangular and ``m > 0`` the stability
  margin, so ``A_k + A_k^T = -2 (B_k B_k^T + m I)`` is negative definite. Every matrix whose
  symmetric part is negative definite (with that margin) has this form, so nothing is lost;
* (a) ``mu_xdot^k = A_k (mu_x^k - x*)``, i.e. each component's linear model vanishes at x*;
* (c) the rest of the joint covariance, ``Sigma_xdot^k = A_k Sigma_x^k A_k^T + Q_k``, ``Q_k`` positive
  definite (optimised for the likelihood objective, estimated from residuals otherwise).

All quantities are in the *scaled attractor frame*: x* at the origin, positions divided by one
scalar ``sx`` and velocities by one scalar ``sv``. A scalar scaling keeps A_k + A_k^T < 0 (a
per-axis scaling would not), so the certificate holds in the caller's units too.

Two options change this (:class:`Layout`):

* ``lyapunov="learned"`` (issue 14, the Lyapunov function of LPV-DS inside SEDS): one shared
  ``P = d M / tr(M)``, ``M = L_P L_P^T`` (``L_P`` lower triangular, positive diagonal; the trace
  normalisation removes the scale that P and the A_k would otherwise share), and
  ``A_k = P^-1 S_k`` with ``S_k = -(B_k B_k^T + m I) + (W_k - W_k^T)``. Then
  ``A_k^T P + P A_k = S_k + S_k^T <= -2 m I`` for every theta, so V(x) = (x - x*)^T P (x - x*)
  decreases along every trajectory of Eq. 5; with ``P = I`` this is the form above.
* ``formulation="constrained"`` (the paper's and the original SEDS code's form): the priors
  ``pi_k`` (bounds (0, 1]), ``mu_x^k``, ``mu_xdot^k`` and the entries of ``A_k`` are free
  variables and Eq. 10 (a), (b), (e) are constraints of the NLP
  (:func:`stability_constraints`): (b) as the leading principal minors of
  ``-(A_k^T P + P A_k) - 2 m I`` (Sylvester's criterion, as the SEDS code does), (a) as
  ``mu_xdot^k - A_k (mu_x^k - x*) = 0``, (e) as ``sum pi_k = 1``; (c) stays the Cholesky factor
  with bounded positive diagonal, (d) the bounds. IPOPT's interior-point method handles them.

The parametrization is defined once, in CasADi (:func:`unpack_casadi`); :func:`unpack_numpy`
evaluates it. The objectives are in :mod:`seds_casadi.core.objectives`; an independent numpy
implementation of both (a test oracle and the SciPy baseline's objective) is in ``tests/oracles.py``.
"""

from __future__ import annotations

import functools

import casadi as ca
import numpy as np

from .settings import Formulation, Lyapunov

__all__ = ["Layout", "unpack_casadi", "unpack_numpy", "stability_constraints"]

#: the constrained form asks the leading minors of -(A^T P + P A) - 2 m I to be at least this
#: (scaled units): strictly positive, so a solution within IPOPT's tolerance is still certified
MINOR_FLOOR = 1e-6
#: smoothing of the model speed in the cosine of Eq. 9 (scaled units), avoids 0/0 at ||f|| = 0
DIRECTION_EPS = 1e-8


class Layout:
    """Index map of the optimisation vector theta for K components in dimension d.

    Parameters
    ----------
    n_components : int
    n_dims : int
    with_noise : bool
        Include the Cholesky factors of Q_k (the likelihood objective needs them).
    lyapunov : Lyapunov or {"identity", "learned"}
        V = |x - x*|^2 (SEDS), or a learned P shared by all components (module docstring).
    formulation : Formulation or {"by-construction", "constrained"}
        Eq. 10 satisfied by the parametrization, or stated as NLP constraints.

    Attributes
    ----------
    lyapunov : Lyapunov
    formulation : Formulation
    constrained : bool
        The constrained form.
    """

    def __init__(self, n_components: int, n_dims: int, with_noise: bool,
                 lyapunov: Lyapunov | str = Lyapunov.IDENTITY,
                 formulation: Formulation | str = Formulation.BY_CONSTRUCTION) -> None:
        self.K = int(n_components)
        self.d = int(n_dims)
        self.with_noise = bool(with_noise)
        self.lyapunov = Lyapunov.parse(lyapunov, "lyapunov")
        self.formulation = Formulation.parse(formulation, "formulation")
        self.constrained = self.formulation is Formulation.CONSTRAINED
        d = self.d
        self.tril = np.array([(i, j) for i in range(d) for j in range(i + 1)], dtype=int)
        self.strict = np.array([(i, j) for i in range(d) for j in range(i)], dtype=int).reshape(-1, 2)
        self.n_tril = len(self.tril)
        self.n_strict = len(self.strict)
        if self.constrained:
            self._blocks = (("pi", 1), ("mu", d), ("mud", d), ("L", self.n_tril), ("A", d * d))
            self.n_logits = 0
        else:
            self._blocks = (("mu", d), ("L", self.n_tril), ("B", self.n_tril),
                            ("W", self.n_strict))
            self.n_logits = self.K - 1
        if with_noise:
            self._blocks += (("Q", self.n_tril),)
        self.per_component = sum(n for _, n in self._blocks)
        self.n_lyapunov = self.n_tril if self.lyapunov is Lyapunov.LEARNED else 0
        self.size = self.n_logits + self.K * self.per_component + self.n_lyapunov

    @property
    def key(self) -> tuple:
        """What determines the layout (K, d, noise, Lyapunov, form): a cache key."""
        return (self.K, self.d, self.with_noise, self.lyapunov.value, self.formulation.value)

    @property
    def lyapunov_slice(self) -> slice:
        """Where L_P sits in theta (empty for ``lyapunov="identity"``)."""
        return slice(self.size - self.n_lyapunov, self.size)

    def slices(self, k: int) -> dict[str, slice]:
        """Slices of component k's blocks in theta: mu, L, B, W (and Q); constrained form:
        pi, mu, mud, L, A (row-major) (and Q)."""
        o = self.n_logits + k * self.per_component
        out = {}
        for name, n in self._blocks:
            out[name] = slice(o, o + n)
            o += n
        return out

    def pack_tril(self, M: np.ndarray) -> np.ndarray:
        """Packed entries of a lower-triangular M with positive diagonal (log on the diagonal):
        the inverse of how :func:`unpack_casadi` builds L, B and L_Q."""
        return np.array([np.log(M[i, j]) if i == j else M[i, j] for i, j in self.tril])


def _tril_sx(v: ca.SX, layout: Layout) -> ca.SX:
    M = ca.SX.zeros(layout.d, layout.d)
    for idx, (i, j) in enumerate(layout.tril):
        M[i, j] = ca.exp(v[idx]) if i == j else v[idx]
    return M


def _tril_inverse_sx(L: ca.SX, d: int) -> ca.SX:
    """Inverse of a lower-triangular matrix by forward substitution (small explicit graph)."""
    inv = ca.SX.zeros(d, d)
    for j in range(d):
        inv[j, j] = 1.0 / L[j, j]
        for i in range(j + 1, d):
            acc = 0
            for m in range(j, i):
                acc += L[i, m] * inv[m, j]
            inv[i, j] = -acc / L[i, i]
    return inv


def lyapunov_sx(theta: ca.SX, layout: Layout) -> tuple[ca.SX, ca.SX]:
    """P = d M / tr(M), M = L_P L_P^T, and its inverse, from theta (learned layouts)."""
    d = layout.d
    L = _tril_sx(theta[layout.lyapunov_slice], layout)
    Linv = _tril_inverse_sx(L, d)
    tr = ca.sumsqr(L)  # tr(L L^T)
    return (d / tr) * (L @ L.T), (tr / d) * (Linv.T @ Linv)


def unpack_casadi(theta: ca.SX, layout: Layout, margin: float) -> dict:
    """Model pieces from theta as SX: the one definition of the parametrization (module docstring).

    Returns a dict of lists over components: ``logpi``, ``mu``, ``L`` (Cholesky factor of
    Sigma_x), ``Linv`` (its inverse), ``logdet`` (log |Sigma_x|), ``A``, and ``LQ``, ``LQinv``,
    ``logdetQ`` with noise factors; ``P`` (the Lyapunov matrix; None for the identity);
    constrained form: ``pi`` (raw priors), ``mud`` (mu_xdot) and ``b`` (mu_xdot - A mu_x, zero
    once Eq. 10a holds).
    """
    K, d = layout.K, layout.d
    constrained = layout.constrained
    keys = ("logpi", "mu", "L", "Linv", "logdet", "A", "LQ", "LQinv", "logdetQ", "pi", "mud", "b")
    out = {k: [] for k in keys}
    P = Pinv = None
    if layout.lyapunov is Lyapunov.LEARNED:
        P, Pinv = lyapunov_sx(theta, layout)
    out["P"] = P
    if not constrained:
        logits = ca.vertcat(theta[: layout.n_logits], 0)
        top = ca.mmax(logits)
        lse = ca.log(ca.sum1(ca.exp(logits - top))) + top
    diag_pos = [idx for idx, (i, j) in enumerate(layout.tril) if i == j]
    for k in range(K):
        s = layout.slices(k)
        out["mu"].append(theta[s["mu"]])
        Lv = theta[s["L"]]
        L = _tril_sx(Lv, layout)
        out["L"].append(L)
        out["Linv"].append(_tril_inverse_sx(L, d))
        out["logdet"].append(2 * sum(Lv[i] for i in diag_pos))
        if constrained:
            pi = theta[s["pi"]]
            out["pi"].append(pi)
            out["logpi"].append(ca.log(pi))
            A = ca.reshape(theta[s["A"]], d, d).T  # row-major
            out["mud"].append(theta[s["mud"]])
            out["b"].append(theta[s["mud"]] - A @ theta[s["mu"]])
        else:
            out["logpi"].append(logits[k] - lse)
            B = _tril_sx(theta[s["B"]], layout)
            W = ca.SX.zeros(d, d)
            for idx, (i, j) in enumerate(layout.strict):
                W[i, j] = theta[s["W"]][idx]
            A = -(B @ B.T + margin * ca.SX.eye(d)) + (W - W.T)
            if Pinv is not None:
                A = Pinv @ A
        out["A"].append(A)
        if layout.with_noise:
            Qv = theta[s["Q"]]
            LQ = _tril_sx(Qv, layout)
            out["LQ"].append(LQ)
            out["LQinv"].append(_tril_inverse_sx(LQ, d))
            out["logdetQ"].append(2 * sum(Qv[i] for i in diag_pos))
    return out


def _leading_minors_sx(M: ca.SX, d: int) -> list:
    return [ca.det(M[:i, :i]) for i in range(1, d + 1)]


def stability_constraints(layout: Layout, margin: float) -> tuple[ca.Function, np.ndarray,
                                                                   np.ndarray]:
    """Eq. 10 (a), (b), (e) as NLP constraints g(theta) with bounds (constrained form).

    (b): the leading principal minors of ``-(A_k^T P + P A_k) - 2 m I`` at least
    :data:`MINOR_FLOOR` (Sylvester: then it is positive definite, so A_k^T P + P A_k < -2 m I);
    (a): ``mu_xdot^k - A_k mu_x^k = 0`` (scaled attractor frame, x* = 0); (e): ``sum pi_k = 1``.

    Returns
    -------
    g : casadi.Function
        theta -> the constraint values (minors of every component, then (a), then (e)).
    lbg, ubg : array
    """
    K, d = layout.K, layout.d
    theta = ca.SX.sym("theta", layout.size)
    p = unpack_casadi(theta, layout, margin)
    P = p["P"] if p["P"] is not None else ca.SX.eye(d)
    minors, eqs = [], []
    for k in range(K):
        A = p["A"][k]
        M = -(A.T @ P + P @ A) - 2 * margin * ca.SX.eye(d)
        minors += _leading_minors_sx(M, d)
        eqs.append(p["b"][k])
    g = ca.vertcat(*minors, *eqs, sum(p["pi"]) - 1)
    lbg = np.r_[np.full(K * d, MINOR_FLOOR), np.zeros(K * d + 1)]
    ubg = np.r_[np.full(K * d, np.inf), np.zeros(K * d + 1)]
    return ca.Function("seds_eq10", [theta], [g]), lbg, ubg


@functools.lru_cache(maxsize=64)
def _unpack_function(K: int, d: int, with_noise: bool, margin: float, lyapunov: Lyapunov,
                     formulation: Formulation) -> ca.Function:
    layout = Layout(K, d, with_noise, lyapunov, formulation)
    theta = ca.SX.sym("theta", layout.size)
    p = unpack_casadi(theta, layout, margin)
    if layout.constrained:
        pri = ca.vertcat(*p["pi"])
        pri = ca.log(pri / ca.sum1(pri))  # (e) exactly: the projection of the raw priors
    else:
        pri = ca.vertcat(*p["logpi"])
    P = p["P"] if p["P"] is not None else ca.SX.eye(d)
    outs = [pri, *p["mu"], *p["L"], *p["A"], P]
    if with_noise:
        outs += p["LQ"]
    # one output, every piece vectorised (column-major): one conversion to numpy instead of
    # one per piece (3 K + 2 of them, 50 us each: 1.6 ms a call at K = 10)
    return ca.Function("unpack", [theta], [ca.vertcat(*[ca.vec(o) for o in outs])])


def unpack_numpy(theta: np.ndarray, layout: Layout, margin: float) -> dict[str, np.ndarray]:
    """Numerical values of :func:`unpack_casadi`: model arrays (scaled attractor frame) from theta.

    Returns
    -------
    dict with ``priors`` (K,), ``mu`` (K, d), ``Sx`` (K, d, d), ``A`` (K, d, d), ``P`` (d, d),
    and ``Q`` (K, d, d) when the layout has noise factors. In the constrained form the priors
    are normalised to sum 1 (the raw ones satisfy Eq. 10e only to IPOPT's tolerance).
    """
    K, d = layout.K, layout.d
    f = _unpack_function(K, d, layout.with_noise, float(margin), layout.lyapunov,
                         layout.formulation)
    flat = np.asarray(f(np.asarray(theta, dtype=float))).ravel()
    pri, rest = flat[:K], flat[K:]
    mu = rest[: K * d].reshape(K, d).copy()
    # the d x d pieces (L_k, A_k, P, L_Q,k) came column-major
    blocks = np.ascontiguousarray(rest[K * d:].reshape(-1, d, d).transpose(0, 2, 1))
    L, A, P = blocks[:K], blocks[K: 2 * K], blocks[2 * K]
    res = {"priors": np.exp(pri), "mu": mu, "Sx": L @ np.transpose(L, (0, 2, 1)), "A": A.copy(),
           "P": 0.5 * (P + P.T)}
    if layout.with_noise:
        LQ = blocks[2 * K + 1:]
        res["Q"] = LQ @ np.transpose(LQ, (0, 2, 1))
    return res
