"""Per-sample objective kernels in CasADi, their exact derivatives, and how IPOPT gets them.

The SEDS objectives are sums over samples, J(theta) = (1/W) sum_i g(theta; x_i, xdot_i, c_i). We
write g for *one* sample symbolically (CasADi SX), take its exact gradient and Hessian by
algorithmic differentiation, and map those small functions over the data with a summing reduction.
This keeps the symbolic graph independent of the number of samples (building takes milliseconds
instead of seconds) while IPOPT still receives exact first and second derivatives.

The kernels can be compiled to C with the system's C compiler (``cc``/``gcc``, through
:mod:`seds_casadi.codegen`), which makes the Hessian about 10x faster than CasADi's virtual
machine. Compiled kernels depend only on (K, d, objective, margin), not on the data, and are
cached on disk by the hash of their C source. Without a compiler, or with ``SEDS_CASADI_JIT=0``,
the same functions run in CasADi's virtual machine.

With a compiler, the sums over samples themselves are compiled as vectorised C loops
(:class:`~seds_casadi.codegen.column_sum.ColumnSum`: four samples per AVX2 instruction, the
Hessian's lower triangle only, numpy arrays passed in place) instead of CasADi's maps: J 6.7x,
grad J 4.6x and Hess J 2.4x faster at K = 6 on 2,000 samples (``benchmarks/README.md``).
``SEDS_CASADI_SIMD=0`` keeps CasADi's compiled maps; ``fit_info["sums"]`` says which ran. The
constrained form keeps CasADi's serial sums (its IPOPT path depends on their order).
"""

from __future__ import annotations

import logging
import os

import casadi as ca
import numpy as np

from ..codegen import UnsupportedOperation, compile_functions, compiler_available
from ..codegen.column_sum import ColumnSum
from .gmm import logsumexp_parts_sx
from .parametrization import DIRECTION_EPS, Layout, unpack_casadi
from .settings import Objective

__all__ = ["sample_objective", "SumKernels", "approach_constraints"]

_LOG = logging.getLogger(__name__)
_LOG_2PI = float(np.log(2.0 * np.pi))


def sample_objective(layout: Layout, objective: Objective | str, margin: float) -> ca.Function:
    """The objective term of one sample, g(theta, x, xdot, c), as an SX Function.

    ``c`` is the sample's coefficient: w_i / ||xdot_i|| for ``"direction"`` (Eq. 9 and 11; 0 for a
    sample at rest), 1 for ``"mse"`` and ``"likelihood"``.

    * direction: g = -c xdot^T f(x) / sqrt(||f(x)||^2 + eps)
    * mse: g = c ||f(x) - xdot||^2
    * likelihood: g = -c log sum_k pi_k N(x; mu_k, Sigma_x^k) N(xdot; A_k x, Q_k)

    with f(x) = sum_k h^k(x) A_k x (Eq. 5 in the attractor frame, where mu_xdot^k = A_k mu_x^k);
    in the constrained form f(x) = sum_k h^k(x) (mu_xdot^k + A_k (x - mu_x^k)), Eq. 5 as written.
    """
    objective = Objective.parse(objective, "objective")
    likelihood = objective is Objective.LIKELIHOOD
    K, d = layout.K, layout.d
    theta = ca.SX.sym("theta", layout.size)
    x = ca.SX.sym("x", d)
    xd = ca.SX.sym("xd", d)
    c = ca.SX.sym("c")
    p = unpack_casadi(theta, layout, margin)
    logp, fk = [], []
    for k in range(K):
        z = p["Linv"][k] @ (x - p["mu"][k])
        a = p["logpi"][k] - 0.5 * (ca.sumsqr(z) + p["logdet"][k] + d * _LOG_2PI)
        F = p["A"][k] @ x
        if p["b"]:  # constrained form: mu_xdot + A (x - mu), equal to A x once Eq. 10a holds
            F = F + p["b"][k]
        if likelihood:
            r = p["LQinv"][k] @ (xd - F)
            a = a - 0.5 * (ca.sumsqr(r) + p["logdetQ"][k] + d * _LOG_2PI)
        logp.append(a)
        fk.append(F)
    m, e, s = logsumexp_parts_sx(logp)
    if likelihood:
        g = -c * (m + ca.log(s))
    else:
        f = fk[0] * (e[0] / s)
        for k in range(1, K):
            f = f + fk[k] * (e[k] / s)
        if objective is Objective.MSE:
            g = c * ca.sumsqr(f - xd)
        else:  # Objective.DIRECTION
            g = -c * ca.dot(f, xd) / ca.sqrt(ca.sumsqr(f) + DIRECTION_EPS)
    return ca.Function("g", [theta, x, xd, c], [g], ["theta", "x", "xd", "c"], ["g"])


def approach_constraints(layout: Layout, margin: float, direction: np.ndarray,
                         ratio: float) -> ca.Function:
    """Constraints that make ``direction`` the slowest way into the target (optional extension).

    With J = sum_k h^k(x*) A_k the linearisation of f at x* (scaled attractor frame, x* = 0),
    u = direction (unit) and Q an orthonormal basis of the plane perpendicular to u:

    * ``Q^T J u = 0`` (d-1 equalities): u is an eigenvector of J, with rate lambda = -u^T J u > 0;
    * ``S = -(M + M^T)/2 - ratio * lambda * I``, M = Q^T J Q, positive definite through its
      leading principal minors m_i (Sylvester), asked as m_i / lambda^(i-1) >= 0.05 lambda
      (d-1 inequalities in the units of lambda): motion across u decays at least ``ratio`` times
      faster than along it.

    Then trajectories line up with u as r^(ratio - 1) while they approach x*, so the target field's
    limit (Eq. 8, 13) is u and is reached quickly. The paper has no such constraint: it is offered
    for hitting motions, whose direction at the ball must not depend on where the swing starts.

    Returns
    -------
    casadi.Function
        theta -> g, with equalities first (``d - 1`` of them, bounds 0) then the minors (>= 0).
    """
    d = layout.d
    u = np.asarray(direction, dtype=float).ravel()
    u = u / np.linalg.norm(u)
    Q = np.linalg.svd(np.eye(d) - np.outer(u, u))[0][:, : d - 1]
    theta = ca.SX.sym("theta", layout.size)
    p = unpack_casadi(theta, layout, margin)
    logp = [p["logpi"][k] - 0.5 * (ca.sumsqr(p["Linv"][k] @ p["mu"][k]) + p["logdet"][k])
            for k in range(layout.K)]
    _, e, tot = logsumexp_parts_sx(logp)
    J = sum((p["A"][k] * (e[k] / tot) for k in range(1, layout.K)), p["A"][0] * (e[0] / tot))
    lam = -ca.dot(ca.DM(u), J @ ca.DM(u))
    eq = ca.DM(Q).T @ J @ ca.DM(u)
    M = ca.DM(Q).T @ J @ ca.DM(Q)
    S = -(M + M.T) / 2 - ratio * lam * ca.DM.eye(d - 1)
    # Sylvester: S positive definite iff its leading minors are > 0; ask for a margin of 5 %
    minors = [ca.det(S[:i, :i]) / lam ** (i - 1) - 0.05 * lam for i in range(1, d)]
    return ca.Function("approach", [theta], [ca.vertcat(eq, *minors)])


#: samples below which the sums over samples run on one thread (threads cost more than they
#: save on small data sets)
THREADED_MIN_SAMPLES = 400


def kernel_threads(n_samples: int) -> int:
    """Threads for the sums over samples: the environment variable ``SEDS_CASADI_THREADS`` if
    set, else 2 on a machine with at least two cores (1 below :data:`THREADED_MIN_SAMPLES`)."""
    env = os.environ.get("SEDS_CASADI_THREADS")
    if env is not None:
        try:
            return max(1, int(env))
        except ValueError:
            raise ValueError(f"SEDS_CASADI_THREADS must be a positive integer, got {env!r}") from None
    if n_samples < THREADED_MIN_SAMPLES:
        return 1
    return min(2, os.cpu_count() or 1)


#: per-thread sample counts above this are summed in blocks (see :func:`sum_layout`)
BLOCKED_MIN_SAMPLES = 64


def sum_layout(n: int, threads: int) -> tuple[int, int]:
    """(chunk, blocks) for summing n samples on ``threads`` threads: each thread sums
    ``blocks`` blocks of ``chunk`` samples (n padded to threads x blocks x chunk).

    CasADi's serial map with a summed output keeps every instance's output until it adds them:
    for the Hessian that is n x P^2 doubles per call (39 MB at n = 2,000, P = 49), allocated
    and zero-filled on every call, beyond the size glibc reuses, so that half of the Hessian's
    time went to page faults (measured in ``benchmarks/README.md``). Blocks of about sqrt(n)
    samples keep it to (chunk + blocks) x P^2; the padding is below sqrt(n) samples per thread.
    """
    q = -(-int(n) // max(1, int(threads)))
    if q <= BLOCKED_MIN_SAMPLES:
        return q, 1
    chunk = int(np.ceil(np.sqrt(q)))
    return chunk, -(-q // chunk)


def _sum_map(f: ca.Function, name: str, chunk: int, blocks: int, reduce_out: list,
             threads: int) -> ca.Function:
    """f summed over threads x blocks x chunk samples (the columns of its data inputs): on
    each of ``threads`` threads, ``blocks`` serial blocks of ``chunk`` serial samples."""
    g = f.map(name + "_chunk", "serial", chunk, [0], reduce_out)
    if blocks > 1:
        g = g.map(name + "_blocks", "serial", blocks, [0], reduce_out)
    if threads <= 1:
        return g
    return g.map(name, "thread", threads, [0], reduce_out, {"max_num_threads": threads})


class SumKernels:
    """J, grad J and Hess J over a data set, from per-sample kernels mapped with a sum.

    Parameters
    ----------
    layout : Layout
    objective : Objective or str
    margin : float
    X, Xd : array, shape (n, d)
        Scaled data in the attractor frame.
    coef : array, shape (n,)
        Per-sample coefficients c_i (see :func:`sample_objective`).
    norm : float
        W: J = (1/W) sum_i g_i.
    compile : bool
        Compile the kernels to C when a compiler is available.
    hessian : bool
        Build the exact per-sample Hessian kernel (not needed with IPOPT's L-BFGS).
    threads : int, optional
        Threads for the sums over samples (default :func:`kernel_threads`).
    blocked : bool
        Sum each thread's samples in blocks (:func:`sum_layout`); False: one serial sum per
        thread, which needs n x P^2 doubles of work for the Hessian.

    Attributes
    ----------
    engine : {"simd", "casadi"}
        Who sums over the samples: the vectorised C loops (with ``compile``, ``blocked``, a C
        compiler and ``SEDS_CASADI_SIMD`` not ``0``) or CasADi's maps.
    """

    def __init__(self, layout: Layout, objective: Objective | str, margin: float, X: np.ndarray,
                 Xd: np.ndarray, coef: np.ndarray, norm: float, compile: bool = True,
                 hessian: bool = True, threads: int | None = None,
                 blocked: bool = True) -> None:
        objective = Objective.parse(objective, "objective")
        key = (layout.K, layout.d, layout.with_noise, layout.lyapunov, layout.formulation,
               objective, float(margin), bool(hessian))
        cached = _KERNELS.get(key)
        if cached is None:
            g = sample_objective(layout, objective, margin)
            th, x, xd, c = g.sx_in()
            gv = g(th, x, xd, c)
            grad = ca.gradient(gv, th)
            fg = ca.Function("g_grad", [th, x, xd, c], [gv, grad])
            funcs = [g, fg]
            if hessian:  # its C grows as P^2 per sample: built only when IPOPT is to use it
                H = ca.densify(ca.hessian(gv, th)[0])
                funcs.append(ca.Function("g_hess", [th, x, xd, c], [H]))
            cached = _KERNELS[key] = {"funcs": funcs, "sources": {}}
            while len(_KERNELS) > _KERNELS_MAX:
                _KERNELS.pop(next(iter(_KERNELS)))
        funcs, g = cached["funcs"], cached["funcs"][0]
        n = X.shape[0]
        threads = kernel_threads(n) if threads is None else max(1, int(threads))
        self.threads = threads
        self.norm = float(norm)
        self.size = layout.size
        self.n_samples = n
        self._grad_cache: tuple[bytes, np.ndarray] | None = None
        # the vectorised sums (codegen.column_sum); the constrained form (blocked=False) keeps
        # CasADi's serial sums, whose order its IPOPT path depends on
        self._simd = None
        if compile and blocked and simd_enabled():
            try:
                self._simd = _SimdSums(funcs, X, Xd, coef, threads, cached["sources"])
            except (RuntimeError, UnsupportedOperation) as exc:
                _LOG.info("vectorised sums unavailable (%s); using CasADi's maps", exc)
        self.engine = "simd" if self._simd is not None else "casadi"
        self.compiled = self._simd is not None
        if self._simd is not None:  # J as a CasADi graph for inspection, in the VM
            self._g = _sum_map(g, "J_sum", n, 1, [0], 1)
            self._data = [ca.DM(X.T), ca.DM(Xd.T), ca.DM(np.asarray(coef, float)).T]
            return
        if compile:
            compiled = compile_functions(funcs)
            self.compiled = compiled[0] is not g
            funcs = compiled
        # the samples padded to threads x blocks x chunk with zero-weight copies of the last
        chunk, blocks = sum_layout(n, threads) if blocked else (-(-n // threads), 1)
        coef = np.asarray(coef, dtype=float)
        pad = threads * blocks * chunk - n
        if pad:
            X = np.vstack([X, np.repeat(X[-1:], pad, 0)])
            Xd = np.vstack([Xd, np.repeat(Xd[-1:], pad, 0)])
            coef = np.r_[coef, np.zeros(pad)]
        self._g = _sum_map(funcs[0], "J_sum", chunk, blocks, [0], threads)
        self._fg = _sum_map(funcs[1], "JG_sum", chunk, blocks, [0, 1], threads)
        self._h = (_sum_map(funcs[2], "H_sum", chunk, blocks, [0], threads) if hessian
                   else None)
        self._data = [ca.DM(X.T), ca.DM(Xd.T), ca.DM(coef).T]

    def value(self, theta) -> float:
        """J(theta)."""
        if self._simd is not None:
            return float(self._simd.value(theta)[0][0, 0]) / self.norm
        return float(self._g(theta, *self._data)) / self.norm

    def gradient(self, theta) -> np.ndarray:
        """grad J(theta), shape (P,). The last result is cached (IPOPT asks several times)."""
        key = np.asarray(theta, dtype=float).tobytes()
        if self._grad_cache is None or self._grad_cache[0] != key:
            if self._simd is not None:
                g = self._simd.value_gradient(theta)[1].ravel() / self.norm
            else:
                g = np.asarray(self._fg(theta, *self._data)[1]).ravel() / self.norm
            self._grad_cache = (key, g)
        return self._grad_cache[1].copy()

    def hessian(self, theta) -> np.ndarray:
        """Hess J(theta), shape (P, P)."""
        if self._simd is not None:
            return self._simd.hessian(theta) / self.norm
        if self._h is None:
            raise ValueError("these kernels were built without the Hessian (limited-memory)")
        return np.asarray(self._h(theta, *self._data)) / self.norm

    def casadi_function(self) -> ca.Function:
        """J as a CasADi Function theta -> J (MX graph over the mapped kernel)."""
        t = ca.MX.sym("theta", self.size)
        return ca.Function("seds_objective", [t], [self._g(t, *self._data) / self.norm])

    def nlp_objective(self):
        """An object f with f(theta) usable as IPOPT's objective with exact derivatives.

        Returns a CasADi callback whose Jacobian is the gradient kernel and whose second Jacobian
        is the Hessian kernel. Keep a reference to it while the solver lives.
        """
        return _Objective(self)


#: the per-sample kernels (CasADi functions and their C sources) of the problems built in this
#: process, by layout, objective, margin and Hessian: a second fit of the same shape of problem
#: (a cross-validation, a benchmark) skips the symbolic construction and the C translation
_KERNELS: dict = {}
_KERNELS_MAX = 16


#: the Gram objective's symbols and functions by (layout, margin), built once per process: the
#: data enter as parameters (G / n, C / n, s / n), so a second fit of the same K and d (the next
#: K candidate's twin in another data set, a cross-validation, a benchmark) skips the symbolic
#: construction, and IPOPT's solver built on them is cached too (:func:`gram_solver`)
_GRAM: dict = {}
_GRAM_MAX = 32


def _gram_symbols(layout: Layout, margin: float) -> dict:
    """theta, the parameter vector p = [vec(G / n); vec(C / n); s / n], J(theta, p) as SX, and
    the Functions of J and grad J (theta, p) -> ..., for ``layout`` and ``margin``."""
    key = (layout.key, float(margin))
    cached = _GRAM.get(key)
    if cached is None:
        Kd, d = layout.K * layout.d, layout.d
        theta = ca.SX.sym("theta", layout.size)
        G, C, s = ca.SX.sym("G", Kd, Kd), ca.SX.sym("C", Kd, d), ca.SX.sym("s")
        M = ca.horzcat(*unpack_casadi(theta, layout, margin)["A"])
        J = ca.trace(M @ G @ M.T) - 2 * ca.trace(M @ C) + s
        p = ca.vertcat(ca.vec(G), ca.vec(C), s)
        cached = _GRAM[key] = {
            "theta": theta, "p": p, "J": J, "key": key,
            "f": ca.Function("seds_gram_objective", [theta, p], [J]),
            "g": ca.Function("seds_gram_gradient", [theta, p], [ca.gradient(J, theta)]),
            "h": None,  # the Hessian is built when first asked: in 7-D (K d = 28 and more)
            #             its expression takes seconds to build
        }
        while len(_GRAM) > _GRAM_MAX:
            _GRAM.pop(next(iter(_GRAM)))
    return cached


class GramKernels:
    """The mean squared velocity error with the GMM fixed, through sufficient statistics.

    With the mixing h^k(x_i) fixed (``SEDS(gmm="fixed")``), f(x_i) = M phi_i with
    M = [A_1 ... A_K] (d x K d) and phi_i = [h^1(x_i) x_i; ...; h^K(x_i) x_i], so

        J = (1/n) sum_i |f(x_i) - xdot_i|^2
          = (1/n) (tr(M G M^T) - 2 tr(M C) + s),   G = sum_i phi_i phi_i^T,
                                                    C = sum_i phi_i xdot_i^T, s = sum_i |xdot_i|^2

    exactly (the same J as :class:`SumKernels`' ``"mse"`` up to rounding; tested), from a
    (K d)-square matrix: one evaluation costs O((K d)^2 d) whatever the number of samples, and
    CasADi differentiates it exactly (gradient and Hessian). The by-construction form only
    (A_k from B_k, W_k and P; the constrained form's b_k would need phi_i = [h x_i; h]).

    The statistics are the parameters of one symbolic J per (K, d, form, margin), built once
    per process (:func:`_gram_symbols`); :attr:`parameters` holds this data's values.

    Parameters
    ----------
    layout : Layout
    margin : float
    gamma : array, shape (n, K)
        The fixed mixing h^k(x_i).
    X, Xd : arrays, shape (n, d)
        Scaled positions (attractor frame) and velocities.
    """

    engine = "gram"
    compiled = False

    def __init__(self, layout: Layout, margin: float, gamma: np.ndarray, X: np.ndarray,
                 Xd: np.ndarray) -> None:
        if layout.constrained:  # ProblemSettings.gram_statistics decides when it is used
            raise ValueError("GramKernels needs the by-construction form")
        n, K = gamma.shape
        d = X.shape[1]
        Phi = (gamma[:, :, None] * X[:, None, :]).reshape(n, K * d)
        G, C, s = Phi.T @ Phi, Phi.T @ Xd, float(np.sum(Xd * Xd))
        #: p = [vec(G / n); vec(C / n); s / n] (column-major, as CasADi's vec)
        self.parameters = np.concatenate([(G / n).ravel(order="F"), (C / n).ravel(order="F"),
                                          [s / n]])
        self._sym = _gram_symbols(layout, margin)
        self._f_theta = None
        self.size, self.n_samples, self.norm, self.threads = layout.size, n, float(n), 1

    def value(self, theta) -> float:
        """J(theta)."""
        return float(self._sym["f"](theta, self.parameters))

    def gradient(self, theta) -> np.ndarray:
        """grad J(theta), shape (P,)."""
        return np.asarray(self._sym["g"](theta, self.parameters)).ravel()

    def hessian(self, theta) -> np.ndarray:
        """Hess J(theta), shape (P, P)."""
        sym = self._sym
        if sym["h"] is None:
            sym["h"] = ca.Function("seds_gram_hessian", [sym["theta"], sym["p"]],
                                   [ca.densify(ca.hessian(sym["J"], sym["theta"])[0])])
        return np.asarray(sym["h"](theta, self.parameters))

    def casadi_function(self) -> ca.Function:
        """J as a CasADi Function theta -> J."""
        return self.nlp_objective()

    def nlp_objective(self) -> ca.Function:
        """J for IPOPT: an SX Function theta -> J (this data's statistics substituted), so
        CasADi supplies its exact derivatives."""
        if self._f_theta is None:
            sym = self._sym
            J = ca.substitute(sym["J"], sym["p"], ca.DM(self.parameters))
            self._f_theta = ca.Function("seds_gram_objective", [sym["theta"]], [J])
        return self._f_theta

    def nlp_parametric(self) -> tuple[ca.SX, ca.SX, ca.SX, tuple]:
        """(theta, p, J(theta, p), key) as SX: the NLP IPOPT is given when the fit has no
        constraints, with :attr:`parameters` as its ``p``; ``key`` names the symbols (layout
        and margin) for a cache of solvers built on them."""
        sym = self._sym
        return sym["theta"], sym["p"], sym["J"], sym["key"]


def simd_enabled() -> bool:
    """Whether the sums over samples may use the vectorised C loops
    (:mod:`seds_casadi.codegen.column_sum`): a C compiler is available and
    ``SEDS_CASADI_SIMD`` is not ``0``."""
    return os.environ.get("SEDS_CASADI_SIMD", "1") != "0" and compiler_available() is not None


class _SimdSums:
    """J, (J, grad J) and Hess J summed over the samples by vectorised C loops: the Hessian's
    lower triangle only (P (P + 1) / 2 sums instead of P^2), mirrored afterwards."""

    def __init__(self, funcs: list[ca.Function], X, Xd, coef, threads: int,
                 sources: dict | None = None) -> None:
        sources = {} if sources is None else sources  # name -> (function, C source), reused
        U = np.vstack([np.asarray(X, float).T, np.asarray(Xd, float).T,
                       np.asarray(coef, float)[None, :]])
        row = U.shape[0] - 1  # c: every objective is proportional to it (0 in the padding)

        def column_sum(f, name):
            f, src = sources.get(name, (f, None))
            cs = ColumnSum(f, U, row, name, threads, source=src)
            sources[name] = (f, cs.source)
            return cs

        self.value = column_sum(funcs[0], "seds_J")
        self.value_gradient = column_sum(funcs[1], "seds_JG")
        self._hess = None
        if len(funcs) > 2:
            P = funcs[2].size1_out(0)
            self._tril = np.tril_indices(P)
            h = sources.get("seds_H", (None,))[0]
            if h is None:
                th, x, xd, c = funcs[2].sx_in()
                H = funcs[2](th, x, xd, c)
                lower = ca.vertcat(*[H[int(i), int(j)] for i, j in zip(*self._tril)])
                h = ca.Function("g_hess_tril", [th, x, xd, c], [lower])
            self._hess = column_sum(h, "seds_H")
            self._P = P

    def hessian(self, theta) -> np.ndarray:
        if self._hess is None:
            raise ValueError("these kernels were built without the Hessian (limited-memory)")
        H = np.zeros((self._P, self._P))
        H[self._tril] = self._hess(theta)[0].ravel()
        return H + np.tril(H, -1).T


class _Callback(ca.Callback):
    """A CasADi callback with one dense output, optionally with a Jacobian factory."""

    def __init__(self, name: str, sp_in: list, sp_out, fn, jacobian=None) -> None:
        ca.Callback.__init__(self)
        self._sp_in, self._sp_out, self._fn, self._jac = sp_in, sp_out, fn, jacobian
        self._keep = []  # callbacks created for derivatives must outlive this one
        self.construct(name, {})

    def get_n_in(self):
        return len(self._sp_in)

    def get_n_out(self):
        return 1

    def get_sparsity_in(self, i):
        return self._sp_in[i]

    def get_sparsity_out(self, i):
        return self._sp_out

    def eval(self, arg):
        return [self._fn(arg[0])]

    def has_jacobian(self):
        return self._jac is not None

    def get_jacobian(self, name, inames, onames, opts):
        return self._jac(self._keep, name, inames, onames, opts)


def _Objective(k: SumKernels) -> _Callback:
    """J as a callback whose Jacobian is the gradient kernel, whose Jacobian is the Hessian."""
    P = k.size
    col, one, row = ca.Sparsity.dense(P, 1), ca.Sparsity.dense(1, 1), ca.Sparsity.dense(1, P)

    def hess_jac(keep, name, inames, onames, opts):
        hess = _Callback("seds_hess", [col, one], ca.Sparsity.dense(P, P), k.hessian)
        keep.append(hess)
        x, o, out = ca.MX.sym("x", P), ca.MX.sym("o", 1), ca.MX.sym("out", 1, P)
        return ca.Function(name, [x, o, out], [hess(x, o), ca.MX(P, 1)], inames, onames, opts)

    def grad_jac(keep, name, inames, onames, opts):
        grad = _Callback("seds_grad", [col, one], row,
                         lambda t: k.gradient(t).reshape(1, -1), jacobian=hess_jac)
        keep.append(grad)
        x, o = ca.MX.sym("x", P), ca.MX.sym("o", 1)
        return ca.Function(name, [x, o], [grad(x, o)], inames, onames, opts)

    return _Callback("seds_obj", [col], one, k.value, jacobian=grad_jac)
