"""The SEDS problem for one data set: scaling, initialisation, bounds and the CasADi kernels.

:func:`build_problem` turns demonstrations into a :class:`SEDSProblem` (paper Section 4.1,
Eq. 4-11): positions and velocities each divided by one scalar (a per-axis scaling would break
A_k + A_k^T < 0), k-means + EM initialisation with the regression matrices projected onto the
stable set, the Eq. 11 weights, and the per-sample objective kernels with exact derivatives.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from ._random import sklearn_random_state
from .demonstrations import Demonstrations
from .gmm import responsibilities
from .lyapunov import LYAPUNOV_DIAG_RANGE, estimate_lyapunov
from .objectives import GramKernels, SumKernels
from .parametrization import Layout, unpack_numpy
from .settings import Hessian, Init, Lyapunov, Objective, ProblemSettings, SpeedCalibration

__all__ = ["SEDSProblem", "build_problem", "direction_weights", "hessian_strategy"]


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
    settings : ProblemSettings
        What the problem was built from (``objective`` is ``settings.objective``).
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
    hessian : Hessian
        The second derivatives IPOPT uses, ``EXACT`` or ``LIMITED_MEMORY``
        (:func:`hessian_strategy`).
    """

    layout: Layout
    settings: ProblemSettings
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
    hessian: Hessian = Hessian.EXACT
    #: theta's model arrays and the responsibilities of each GMM met so far (the fit reads them
    #: three times for the same theta: speed factor, model arrays, Lyapunov matrix; a fixed GMM
    #: has the same responsibilities at theta0 and at the solution)
    _memo: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def objective(self) -> Objective:
        """The objective J (``settings.objective``)."""
        return self.settings.objective

    def speed_factor(self, theta: np.ndarray,
                     how: SpeedCalibration | str = SpeedCalibration.MEDIAN) -> float:
        """The factor c > 0 that gives a direction-objective model the demonstrated speeds.

        The direction objective (Eq. 9) fixes f only up to a positive factor (scaling every A_k
        by c > 0 changes neither the directions, so neither h = f/||f|| of Eq. 8, nor the
        stability). The returned model is scaled by c so that it moves at the demonstrated
        speeds:

        * ``"median"`` (default): c = median_i ||xdot_i|| / ||f_i||, over the samples that move:
          the model's speed along the demonstrations is then the demonstrated one at the median
          sample, whatever a few samples with a large ||f|| do;
        * ``"least-squares"``: c = sum_i f_i . xdot_i / sum_i ||f_i||^2, dominated by the
          samples where ||f|| is largest (on LASA CShape it gave 0.018x the demonstrated speed
          at the median sample).

        Returns 1 if no sample gives a positive factor. ``"strength"`` (the gains under a
        strength factor) is ``"median"``.
        """
        how = SpeedCalibration.parse(how, "speed_calibration")
        p = self._model_params(theta)
        return _speed_factor(p["A"], self._responsibilities(p), self.X, self.Xd, how)

    def _responsibilities(self, p: dict) -> np.ndarray:
        """:func:`responsibilities` of the GMM of ``p`` at the data (memoised by its numbers)."""
        key = ("h", p["priors"].tobytes(), p["mu"].tobytes(), p["Sx"].tobytes())
        h = self._memo.get(key)
        if h is None:
            h = self._memo[key] = responsibilities(self.X, p["priors"], p["mu"], p["Sx"])
        return h

    def _model_params(self, theta: np.ndarray) -> dict[str, np.ndarray]:
        """:func:`unpack_numpy` with a Sigma_x whose smallest eigenvalue is below
        :data:`COVARIANCE_FLOOR` times its largest raised by that much: a component that
        collapsed onto a subspace of the data (seen in 7-D joint space, eigenvalues 1e-17 to
        1e3) keeps an invertible Sigma_x; other components are untouched. A_k is unchanged
        (the model's Sigma_xdotx is built from the floored Sigma_x). Memoised by theta; the
        caller gets its own copies."""
        theta = np.asarray(theta, dtype=float)
        key = ("p", theta.tobytes())
        p = self._memo.get(key)
        if p is not None:
            return {k: v.copy() for k, v in p.items()}
        p = unpack_numpy(theta, self.layout, self.margin)
        d = self.layout.d
        for k in range(self.layout.K):
            ev = np.linalg.eigvalsh(p["Sx"][k])
            if ev[0] < COVARIANCE_FLOOR * ev[-1]:  # only a numerically singular Sigma_x
                p["Sx"][k] = p["Sx"][k] + COVARIANCE_FLOOR * ev[-1] * np.eye(d)
        self._memo[key] = p
        return {k: v.copy() for k, v in p.items()}

    def lyapunov_matrix(self, theta: np.ndarray) -> np.ndarray:
        """P of V(x) = (x - x*)^T P (x - x*) for a given theta (the identity unless learned);
        the same in the caller's coordinates (a scalar scaling changes V only by a factor)."""
        return self._model_params(theta)["P"]

    def to_model_arrays(self, theta: np.ndarray, speed_factor: float | None = None
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Priors, means and joint covariances in the caller's coordinates for a given theta.

        Sigma_xdot = A Sigma_x A^T + Q with Q the optimised noise (likelihood) or the
        responsibility-weighted residual covariance of the data (other objectives). For the
        direction objective the A_k are scaled by :meth:`speed_factor` first (pass it as
        ``speed_factor`` if already computed). In the constrained form, the priors are
        normalised and mu_xdot^k = A_k (mu_x^k - x*) is imposed exactly (Eq. 10 e and a hold
        there only to IPOPT's tolerance; ``fit_info["constraint_violation"]`` reports it).
        """
        p = self._model_params(theta)
        K, d = self.layout.K, self.layout.d
        sx, sv = self.position_scale, self.velocity_scale
        if "Q" in p:
            Q = p["Q"]
        else:
            h = self._responsibilities(p)
            if self.objective is Objective.DIRECTION:
                c = speed_factor if speed_factor is not None else _speed_factor(
                    p["A"], h, self.X, self.Xd)
                p["A"] = p["A"] * c
            Q = np.empty((K, d, d))
            for k in range(K):
                r = self.Xd - self.X @ p["A"][k].T
                wk = h[:, k] / max(h[:, k].sum(), 1e-300)
                # the floor grows with A Sigma_x A^T: Q is the Schur complement of the joint
                # covariance, so a floor far below that block's size is lost to rounding when
                # the data are fitted exactly (7-D linear data, a fixed GMM: eigenvalue -3e-11)
                AS = p["A"][k] @ p["Sx"][k] @ p["A"][k].T
                floor = 1e-6 + 1e-8 * float(np.linalg.norm(AS, 2))
                Q[k] = (r * wk[:, None]).T @ r + floor * np.eye(d)
        means = np.empty((K, 2 * d))
        covs = np.empty((K, 2 * d, 2 * d))
        for k in range(K):
            A = p["A"][k] * (sv / sx)
            Sx = p["Sx"][k] * sx**2
            mx = p["mu"][k] * sx
            means[k, :d] = mx + self.target
            covs[k, :d, :d] = Sx
            covs[k, d:, :d] = A @ Sx
            covs[k, :d, d:] = (A @ Sx).T
            covs[k, d:, d:] = A @ Sx @ A.T + Q[k] * sv**2
            covs[k] = 0.5 * (covs[k] + covs[k].T)
            # Eq. 10a with the A_k that the model recovers from its covariances (Sigma_xdotx
            # Sigma_x^-1, as StableDS and the certificate compute it): for a thin component the
            # recovered A differs from the optimised one by cond(Sigma_x) eps
            A_model = np.linalg.solve(covs[k, :d, :d].T, covs[k, d:, :d].T).T
            means[k, d:] = A_model @ mx
        return p["priors"].copy(), means, covs


#: smallest eigenvalue ratio of a returned Sigma_x (see :meth:`SEDSProblem._model_params`)
COVARIANCE_FLOOR = 1e-10
#: variance added to the EM covariances of the initialisation (scaled units: positions and
#: velocities of unit RMS), by dimension. In 4-D and above the components' samples rarely span
#: every dimension (7-D joint-space putts: data variances 2e-5 .. 2), EM's components collapse
#: and their regression matrices start IPOPT in a poor basin: WAM joint space, direction
#: objective, K = 3: e_dot 0.66 with 1e-6, 0.06 with 1e-2 (K = 2, 5: 0.08 / 0.09 -> 0.07 / 0.06).
#: Up to 3-D it stays 1e-6, with which every measurement in benchmarks/README.md was made.
INIT_REG_COVAR = 1e-6
INIT_REG_COVAR_HIGH_D = 1e-2


def _speed_factor(A, h, X, Xd, how: SpeedCalibration = SpeedCalibration.MEDIAN) -> float:
    F = np.einsum("nk,kij,nj->ni", h, A, X)
    if how is SpeedCalibration.LEAST_SQUARES:  # "strength" models keep the median-calibrated
        num, den = float(np.sum(F * Xd)), float(np.sum(F * F))  # gains under v(x)
        return num / den if (num > 0 and den > 0) else 1.0
    nf, nv = np.linalg.norm(F, axis=1), np.linalg.norm(Xd, axis=1)
    ok = (nf > 1e-12 * max(nf.max(), 1e-300)) & (nv > 1e-12 * max(nv.max(), 1e-300))
    if not ok.any():
        return 1.0
    c = float(np.exp(np.median(np.log(nv[ok]) - np.log(nf[ok]))))
    return c if np.isfinite(c) and c > 0 else 1.0


#: the physically-consistent similarity is built on at most this many samples (evenly strided);
#: the others take the resulting GMM's posterior
PC_MAX_SAMPLES = 1000


def pc_similarity(X: np.ndarray, Xd: np.ndarray) -> np.ndarray:
    """The physically-consistent similarity of PC-GMM (Figueroa and Billard, CoRL 2018; as in
    their phys-gmm code): s_ij = exp(-l |x_i - x_j|) (1 + cos angle(xdot_i, xdot_j)), with
    l = 1 / (2 sigma^2) and sigma^2 half the mode of the pairwise distances' histogram. Two
    samples are similar when they are close *and* move the same way, so that a cluster follows
    one locally linear piece of the motion. A zero velocity counts as cos = 0."""
    from scipy.spatial.distance import pdist, squareform

    D = pdist(X)
    counts, edges = np.histogram(D, bins="auto")
    mode = 0.5 * (edges[np.argmax(counts)] + edges[np.argmax(counts) + 1])
    sigma2 = max(mode, 1e-6 * max(float(D.max(initial=0.0)), 1e-300)) / 2.0
    speed = np.linalg.norm(Xd, axis=1)
    U = np.divide(Xd, speed[:, None], out=np.zeros_like(Xd), where=speed[:, None] > 0)
    return np.exp(-squareform(D) / (2.0 * sigma2)) * (1.0 + U @ U.T)


@dataclass(frozen=True)
class PCEmbedding:
    """The spectral embedding of :func:`pc_similarity` on the (strided) samples of a data set,
    computed once and shared by the K tried (``SEDS(n_components="auto")``).

    Attributes
    ----------
    stride : int
        The samples used are ``X[::stride]``.
    maps : array, shape (n_used, n_columns)
        scikit-learn's ``spectral_embedding`` (``drop_first=False``), as ``SpectralClustering``
        computes it; K clusters take its first K columns.
    state : tuple
        The random state after the embedding (each K's k-means starts from it, as
        ``SpectralClustering`` would).
    labels : dict
        K -> a future of that K's k-means labels, when :func:`prefetch_labels` started them
        in the background.
    """

    stride: int
    maps: np.ndarray
    state: tuple
    labels: dict = field(default_factory=dict, compare=False, repr=False)


#: threadpoolctl's controller for the k-means' one-thread limit (made once: scanning the loaded
#: libraries takes 3.5 ms, as long as a k-means run itself)
_THREADPOOLS: list = []


def _one_thread():
    """A context in which the BLAS and OpenMP pools run one thread."""
    from threadpoolctl import ThreadpoolController

    if not _THREADPOOLS:
        _THREADPOOLS.append(ThreadpoolController())  # after scikit-learn loaded its OpenMP
    return _THREADPOOLS[0].limit(limits=1)


def _kmeans_labels(embedding: PCEmbedding, K: int) -> np.ndarray:
    """The K clusters of the embedding's first K columns (k-means from its random state)."""
    from sklearn.cluster import k_means

    rs = np.random.RandomState()
    rs.set_state(embedding.state)
    # one thread: on 1,000 samples OpenMP's threads cost more than they save, and on busy cores
    # they wait for each other (a run of Lloyd took 0.12 s with two threads on two loaded
    # cores, a few ms on one)
    with _one_thread():
        _, labels, _ = k_means(embedding.maps[:, :K], K, random_state=rs, n_init=10)
    return labels


def prefetch_labels(embedding: PCEmbedding, Ks) -> Callable[[], None]:
    """Start each K's k-means (in the order given) on a background thread, while the caller
    fits the K before it (scikit-learn's k-means runs mostly without the GIL); the same labels
    as computed in line. Returns a function that cancels those not started yet (call it when
    the caller stops early)."""
    from concurrent.futures import ThreadPoolExecutor

    pool = ThreadPoolExecutor(1, thread_name_prefix="seds-kmeans")
    for K in Ks:
        embedding.labels[K] = pool.submit(_kmeans_labels, embedding, K)
    pool.shutdown(wait=False)

    def cancel() -> None:
        for fut in embedding.labels.values():
            fut.cancel()
    return cancel


def pc_embedding(X: np.ndarray, Xd: np.ndarray, n_columns: int, random_state) -> PCEmbedding:
    """The spectral embedding of PC-GMM's similarity, in ``n_columns`` dimensions.

    scikit-learn's ``spectral_embedding(affinity, drop_first=False)`` with ARPACK, step by
    step: the normalised Laplacian L with a unit diagonal, its ``n_columns`` eigenvectors
    nearest to 0 by shift-invert about -1e-5 from ARPACK's start ``uniform(-1, 1)`` drawn from
    the random state, divided by the degrees' square roots, with scikit-learn's sign rule.
    L + 1e-5 I is positive definite, so it is solved by a Cholesky factor (half the work of
    the LU factors scipy's shift-invert uses on a dense matrix), and the checks made for any
    affinity (symmetry, connectedness: only a warning) are left out: on the 26 LASA shapes the
    embedding agrees with scikit-learn 1.9's to 4e-15 and leaves the same random state, in
    48 instead of 57 ms.

    Parameters
    ----------
    X, Xd : array, shape (n, d)
        Positions and velocities in the problem's scaled frame (:func:`data_scales`).
    n_columns : int
        The largest K it will serve.
    random_state : int, RandomState or None
    """
    from scipy.linalg import cho_factor, cho_solve
    from scipy.sparse.csgraph import laplacian
    from scipy.sparse.linalg import LinearOperator, eigsh
    from sklearn.utils import check_random_state
    from sklearn.utils.extmath import _deterministic_vector_sign_flip

    stride = max(1, int(np.ceil(len(X) / PC_MAX_SAMPLES)))
    Xs, Xds = X[::stride], Xd[::stride]
    rs = check_random_state(sklearn_random_state(random_state))
    n, k = len(Xs), int(n_columns)
    L, root_degree = laplacian(pc_similarity(Xs, Xds), normed=True, return_diag=True)
    L.flat[:: n + 1] = 1.0
    v0 = rs.uniform(-1, 1, n)  # scikit-learn's _init_arpack_v0
    if k >= n:  # ARPACK needs k < n: every eigenvector, by a dense solve
        _, V = np.linalg.eigh(L)
    else:
        shift = 1e-5
        factor = cho_factor(L + shift * np.eye(n), lower=True, check_finite=False)
        inverse = LinearOperator((n, n), dtype=float,
                                 matvec=lambda b: cho_solve(factor, b, check_finite=False))
        _, V = eigsh(L, k=k, sigma=-shift, which="LM", tol=0, v0=v0, OPinv=inverse)
    maps = _deterministic_vector_sign_flip(V.T[:k] / root_degree).T
    return PCEmbedding(stride, maps, rs.get_state())


def _pc_gmm(X: np.ndarray, Xd: np.ndarray, K: int, random_state, reg: float,
            embedding: PCEmbedding | None = None):
    """Weights, means and covariances of K Gaussians on the positions, from a spectral
    clustering of :func:`pc_similarity` into K clusters.

    PC-GMM itself samples a distance-dependent Chinese restaurant process whose prior is this
    similarity and so also chooses K; here K is the learner's ``n_components`` and the clusters
    come from the similarity's spectral embedding (our choice: deterministic given the seed,
    about 0.1 s on 1,000 samples, and the same notion of a physically-consistent cluster):
    scikit-learn's ``SpectralClustering(affinity="precomputed", assign_labels="kmeans")``
    step by step, so that ``embedding`` (:func:`pc_embedding`, with at least K columns) can be
    shared by several K."""
    if embedding is None or embedding.maps.shape[1] < K:
        embedding = pc_embedding(X, Xd, K, random_state)
    future = embedding.labels.get(K)
    labels = (future.result() if future is not None and not future.cancelled()
              else _kmeans_labels(embedding, K))
    Xs = X[::embedding.stride]
    d = X.shape[1]
    weights, means, covs = np.zeros(K), np.zeros((K, d)), np.zeros((K, d, d))
    for k in range(K):
        pts = Xs[labels == k]
        weights[k] = max(len(pts), 1)
        if len(pts) == 0:  # spectral clustering gave fewer clusters: a broad, light spare
            pts = Xs       # (never seen on the 26 LASA shapes at K = 4-8)
        means[k] = pts.mean(axis=0)
        covs[k] = (np.cov(pts.T, bias=True).reshape(d, d) if len(pts) > 1 else np.zeros((d, d)))
        covs[k] += reg * np.eye(d)
    return weights / weights.sum(), means, covs


#: the LPV start's solvers by (K, d, margin, Hessian): the data (G, C, P0^-1) are parameters,
#: so each is built once per process (0.01-0.07 s each on 2-D LASA)
_LPV_SOLVERS: dict = {}
_LPV_SOLVERS_MAX = 32


def _lpv_solver(K: int, d: int, margin: float, limited: bool) -> tuple:
    """(solver, A(z, p) Function) of :func:`_stable_gains_lpv` for K gains in d dimensions;
    p = [vec(G); vec(C); vec(P0^-1)]."""
    key = (K, d, float(margin), limited)
    cached = _LPV_SOLVERS.pop(key, None)  # taken out while used (threads build their own)
    if cached is not None:
        return key, cached
    tril = [(i, j) for i in range(d) for j in range(i + 1)]
    strict = [(i, j) for i in range(d) for j in range(i)]
    G, C, Pinv = ca.SX.sym("G", K * d, K * d), ca.SX.sym("C", K * d, d), ca.SX.sym("Pinv", d, d)
    z, A_all = [], []
    for k in range(K):
        b = ca.SX.sym(f"b{k}", len(tril))
        w = ca.SX.sym(f"w{k}", len(strict))
        B, W = ca.SX.zeros(d, d), ca.SX.zeros(d, d)
        for idx, (i, j) in enumerate(tril):
            B[i, j] = b[idx]
        for idx, (i, j) in enumerate(strict):
            W[i, j] = w[idx]
        S = -(B @ B.T + margin * ca.DM.eye(d)) + (W - W.T)
        A_all.append(Pinv @ S)
        z += [b, w]
    M = ca.horzcat(*A_all)  # d x K d: F_i = M Phi_i
    f = ca.trace(M @ G @ M.T) - 2 * ca.trace(M @ C)
    p = ca.vertcat(ca.vec(G), ca.vec(C), ca.vec(Pinv))
    nlp = {"x": ca.vertcat(*z), "p": p, "f": f}
    opts = {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes",
            "ipopt.max_iter": 300}
    if limited:  # as the joint problem's Hessian
        opts["ipopt.hessian_approximation"] = "limited-memory"
    solver = ca.nlpsol("lpv_gains", "ipopt", nlp, opts)
    return key, (solver, ca.Function("A", [ca.vertcat(*z), p], A_all))


def _stable_gains_lpv(gamma: np.ndarray, X: np.ndarray, Xd: np.ndarray, P0: np.ndarray,
                      margin: float, A_start: list) -> list:
    """The A_k of least velocity error with the mixing ``gamma`` (n, K) fixed and
    A_k^T P0 + P0 A_k <= -2 m I by construction (LPV-DS's second step, Figueroa and
    Billard 2018, solved here by IPOPT with A_k = P0^-1 (-(B_k B_k^T + m I) + W_k - W_k^T), the
    learner's form of the stable set).

    The error sum_i |sum_k gamma_ik A_k x_i - xdot_i|^2 is a quadratic form in [A_1 .. A_K]
    with the (K d)-square Gram matrix of the features gamma_ik x_i, so the problem's size does
    not grow with the number of samples; the Gram matrix, the cross term and P0^-1 are the
    parameters of a solver built once per process for each (K, d, margin) (:func:`_lpv_solver`).
    """
    n, K = gamma.shape
    d = X.shape[1]
    Phi = (gamma[:, :, None] * X[:, None, :]).reshape(n, K * d)
    G, C = Phi.T @ Phi / n, Phi.T @ Xd / n
    tril = [(i, j) for i in range(d) for j in range(i + 1)]
    strict = [(i, j) for i in range(d) for j in range(i)]
    z0 = []
    for k in range(K):
        Lb, skew = _stable_factors(A_start[k], P0, margin)
        z0 += [Lb[i, j] for i, j in tril] + [skew[i, j] for i, j in strict]
    limited = len(z0) > GRAM_EXACT_HESSIAN_MAX_PARAMETERS
    key, (solver, fA) = _lpv_solver(K, d, margin, limited)
    p = np.concatenate([G.ravel(order="F"), C.ravel(order="F"),
                        np.linalg.inv(P0).ravel(order="F")])
    sol = solver(x0=np.array(z0), p=p)
    _LPV_SOLVERS[key] = (solver, fA)
    while len(_LPV_SOLVERS) > _LPV_SOLVERS_MAX:
        _LPV_SOLVERS.pop(next(iter(_LPV_SOLVERS)))
    A = fA(sol["x"], p)
    out = [np.asarray(a) for a in A] if K > 1 else [np.asarray(A)]
    if not all(np.all(np.isfinite(a)) for a in out):
        return A_start
    return out


def _em(data: np.ndarray, K: int, d: int, random_state):
    """k-means + EM, full covariances, with the initialisation's ``reg_covar`` for dimension d."""
    from sklearn.mixture import GaussianMixture

    return GaussianMixture(
        n_components=K, covariance_type="full", init_params="kmeans",
        reg_covar=INIT_REG_COVAR if d <= 3 else INIT_REG_COVAR_HIGH_D,
        random_state=sklearn_random_state(random_state), max_iter=200,
    ).fit(data)


def _project_stable(A: np.ndarray, P0: np.ndarray, margin: float) -> np.ndarray:
    """The nearest gain to A that is stable for P0: S = P0 A split into symmetric and skew
    parts, the symmetric part's eigenvalues clipped to at most -max(5 % of its largest
    magnitude, 2 m), A = P0^-1 S."""
    PA = P0 @ A
    ev, V = np.linalg.eigh(0.5 * (PA + PA.T))
    ev = np.minimum(ev, -max(0.05 * np.max(np.abs(ev)), 2.0 * margin, 1e-3))
    return np.linalg.solve(P0, V @ np.diag(ev) @ V.T + 0.5 * (PA - PA.T))


def _stable_factors(A: np.ndarray, P0: np.ndarray, margin: float):
    """B (lower triangular) and the skew part K of S = P0 A = -(B B^T + m I) + K, for a gain A
    stable for P0 (B B^T's eigenvalues floored at 1e-10 against rounding)."""
    d = len(A)
    PA = P0 @ A
    ev, V = np.linalg.eigh(-0.5 * (PA + PA.T) - margin * np.eye(d))
    BB = V @ np.diag(np.maximum(ev, 1e-10)) @ V.T
    return np.linalg.cholesky(0.5 * (BB + BB.T)), 0.5 * (PA - PA.T)


def _pack_theta(layout: Layout, P0: np.ndarray, margin: float, weights: np.ndarray,
                means: np.ndarray, covariances: np.ndarray, gains: list, X: np.ndarray,
                Xd: np.ndarray, resp: np.ndarray | None) -> np.ndarray:
    """theta of a GMM over the positions (weights, means, Sigma_x) with stable gains A_k, in
    the layout's form (and the noise covariances of the residuals, weighted by ``resp``)."""
    d = layout.d
    theta = np.zeros(layout.size)
    constrained = layout.constrained
    if not constrained:
        logits = np.log(np.maximum(weights, 1e-12))
        theta[: layout.n_logits] = logits[:-1] - logits[-1]
    if layout.lyapunov is Lyapunov.LEARNED:
        theta[layout.lyapunov_slice] = layout.pack_tril(np.linalg.cholesky(P0))
    for k in range(layout.K):
        s, A, mu = layout.slices(k), gains[k], means[k]
        theta[s["mu"]] = mu
        theta[s["L"]] = layout.pack_tril(np.linalg.cholesky(covariances[k] + 1e-6 * np.eye(d)))
        if constrained:
            theta[s["pi"]] = max(weights[k], 1e-6)
            theta[s["mud"]] = A @ mu
            theta[s["A"]] = A.ravel()
        else:
            B, skew = _stable_factors(A, P0, margin)
            theta[s["B"]] = layout.pack_tril(B)
            theta[s["W"]] = [skew[i, j] for i, j in layout.strict]
        if layout.with_noise:
            r = Xd - X @ A.T
            wk = resp[:, k]
            Q = (r * (wk / max(wk.sum(), 1e-300))[:, None]).T @ r + 1e-4 * np.eye(d)
            theta[s["Q"]] = layout.pack_tril(np.linalg.cholesky(Q))
    return theta


def _initial_theta(
    layout: Layout, X: np.ndarray, Xd: np.ndarray, margin: float, random_state,
    P0: np.ndarray | None = None, init: Init = Init.JOINT_EM,
    embedding: PCEmbedding | None = None,
) -> np.ndarray:
    """k-means + EM on the joint (x, xdot) data, then projected onto the stable set.

    The GMR gain A_k = Sigma_xdotx Sigma_x^-1 of each EM component is projected onto the gains
    stable for P0 (P0 = I unless a Lyapunov matrix is learned; :func:`_project_stable`).

    With ``Init.LPV``, as LPV-DS: EM on the positions alone gives the priors, means and
    covariances (so the mixing is that GMM's posterior), and the A_k are those of least
    velocity error under that mixing, stable for P0 (:func:`_stable_gains_lpv`, started from the
    projected GMR gains of the joint EM's nearest components). ``Init.PC``: the same with the
    GMM of :func:`_pc_gmm`, started from each cluster's weighted least-squares gain, projected
    (no joint EM).
    """
    K, d = layout.K, layout.d
    P0 = np.eye(d) if P0 is None else np.asarray(P0, dtype=float)
    if init is Init.PC:  # no joint EM: the start gains are each cluster's weighted regression
        weights, means, covs = _pc_gmm(X, Xd, K, random_state,
                                       INIT_REG_COVAR if d <= 3 else INIT_REG_COVAR_HIGH_D,
                                       embedding)
        gamma = responsibilities(X, weights, means, covs)
        start = []
        for k in range(K):
            Xw = X * gamma[:, k:k + 1]
            XtX = Xw.T @ X
            ridge = START_GAIN_RIDGE * np.trace(XtX) / d
            A = np.linalg.lstsq(XtX + ridge * np.eye(d), Xw.T @ Xd, rcond=None)[0].T
            start.append(_project_stable(A, P0, margin))
        gains = _stable_gains_lpv(gamma, X, Xd, P0, margin, start)
        return _pack_theta(layout, P0, margin, weights, means, covs, gains, X, Xd, gamma)
    joint = np.hstack([X, Xd])
    gm = _em(joint, K, d, random_state)
    Sx = gm.covariances_[:, :d, :d]
    gmr = [_project_stable(np.linalg.solve(Sx[k] + 1e-6 * np.eye(d),
                                           gm.covariances_[k, :d, d:]).T, P0, margin)
           for k in range(K)]  # Sigma_xdotx Sigma_x^-1, projected
    if init is Init.JOINT_EM:
        resp = gm.predict_proba(joint) if layout.with_noise else None
        return _pack_theta(layout, P0, margin, gm.weights_, gm.means_[:, :d], Sx, gmr, X, Xd,
                           resp)
    gx = _em(X, K, d, random_state)
    weights, means, covs = gx.weights_, gx.means_, gx.covariances_
    gamma = responsibilities(X, weights, means, covs)
    nearest = [int(np.argmin(np.sum((gm.means_[:, :d] - m) ** 2, axis=1))) for m in means]
    gains = _stable_gains_lpv(gamma, X, Xd, P0, margin, [gmr[j] for j in nearest])
    return _pack_theta(layout, P0, margin, weights, means, covs, gains, X, Xd, gamma)


def data_scales(X: np.ndarray, Xd: np.ndarray) -> tuple[float, float]:
    """The problem's scales (sx, sv): the RMS position and velocity per dimension, about the
    target (the problem works on X / sx and Xd / sv)."""
    d = X.shape[1]
    sx = float(np.sqrt(np.mean(np.sum(X**2, axis=1)) / d))
    sv = float(np.sqrt(np.mean(np.sum(Xd**2, axis=1)) / d))
    return sx, sv


#: ridge of each cluster's weighted least-squares start gain, relative to the mean eigenvalue
#: of its normal matrix (1e-9 absolute before: on LASA's Line, data along one direction gave
#: start gains of 1e5 across it, a start 1e6 times the optimum's error)
START_GAIN_RIDGE = 1e-3


def build_problem(demos: Demonstrations, settings: ProblemSettings,
                  embedding: PCEmbedding | None = None,
                  lyapunov0: np.ndarray | None = None) -> SEDSProblem:
    """Scale the data, initialise by k-means + EM and build the CasADi problem.

    Parameters
    ----------
    demos : Demonstrations
    settings : ProblemSettings
        K and the modes (:class:`~seds_casadi.core.seds.SEDS`'s parameters of the same names).
        With ``lyapunov="learned"`` the initial P is
        :func:`~seds_casadi.core.lyapunov.estimate_lyapunov` of the data.
    embedding : PCEmbedding, optional
        With ``init="pc"``: the spectral embedding of these demonstrations (:func:`pc_embedding`
        on the scaled samples), shared by several K; computed here otherwise.
    lyapunov0 : array, shape (d, d), optional
        With ``lyapunov="learned"``: the initial P, :func:`estimate_lyapunov` of these
        demonstrations' scaled samples (shared by several K); computed here otherwise.
    """
    if not isinstance(demos, Demonstrations):
        raise TypeError(
            f"fit expects a seds_casadi.Demonstrations, got {type(demos).__name__}; "
            "wrap your arrays with Demonstrations(positions, dt=...)"
        )
    if not isinstance(settings, ProblemSettings):
        raise TypeError(f"build_problem takes a ProblemSettings, got {type(settings).__name__}")
    K = settings.n_components
    if K is None:
        raise ValueError("the settings have no n_components: choose K first (e.g. by "
                         "bic_n_components, as SEDS(n_components='bic') does)")
    margin = settings.stability_margin
    X, Xd, phase, _ = demos.stacked()
    d = X.shape[1]
    layout = Layout(K, d, with_noise=settings.with_noise, lyapunov=settings.lyapunov,
                    formulation=settings.formulation)
    # each sample gives d velocity equations; ask for at least one per parameter
    if X.shape[0] * d < layout.size or X.shape[0] < 2 * K:
        raise ValueError(
            f"{X.shape[0]} samples are too few for n_components={K} in "
            f"{d}-D ({layout.size} parameters, {X.shape[0] * d} velocity values); use fewer "
            "components or more samples"
        )
    sx, sv = data_scales(X, Xd)
    if not (sx > 0 and sv > 0):
        raise ValueError("the demonstrations do not move away from the target; nothing to learn")
    check_approach(demos, X, Xd)
    Xs, Xds = X / sx, Xd / sv
    direction = settings.objective is Objective.DIRECTION
    if direction:
        w = direction_weights(phase, settings.omega_lower, settings.omega_upper)
    else:
        w = np.ones(len(X))
    P0 = None
    if settings.learned_lyapunov:
        P0 = estimate_lyapunov(Xs, Xds) if lyapunov0 is None else np.asarray(lyapunov0, float)
    theta0 = _initial_theta(layout, Xs, Xds, margin, settings.random_state, P0, settings.init,
                            embedding)
    lbx, ubx = _bounds(layout, settings.gain_limit)
    theta0 = np.clip(theta0, lbx + 1e-9, ubx - 1e-9)
    if settings.fixed_gmm:  # IPOPT takes x_i with lbx_i = ubx_i as a parameter of the problem
        idx = gmm_indices(layout)
        lbx[idx] = ubx[idx] = theta0[idx]
    if direction:  # Eq. 9: w_i cos = (w_i / |xdot_i|) xdot_i . f / |f|
        speed = np.linalg.norm(Xds, axis=1)
        moving = speed > 0
        coef = np.where(moving, w / np.where(moving, speed, 1.0), 0.0)
        norm = float(np.sum(w))
    else:
        coef = np.ones(len(Xs))
        norm = float(len(Xs))
    strategy = hessian_strategy(settings.hessian, layout.size)
    memo: dict = {}
    # the constrained form stays on one thread: its IPOPT path is sensitive to the order of
    # the sums (a 2-D test problem converged serially and ended 1.8e-6 infeasible at the
    # iteration limit with two threads), and to the blocked sums too (the test problems of
    # tests/test_lyapunov.py ended 0.33 and 2.4e-6 infeasible): it keeps one serial sum
    if settings.gram_statistics:
        # the mixing is fixed: the squared error is a quadratic form in the gains whose
        # (K d)-square statistics replace the sums over samples (exact, independent of n)
        p0 = unpack_numpy(theta0, layout, margin)
        gamma = responsibilities(Xs, p0["priors"], p0["mu"], p0["Sx"])
        memo[("h", p0["priors"].tobytes(), p0["mu"].tobytes(), p0["Sx"].tobytes())] = gamma
        kernels = GramKernels(layout, margin, gamma, Xs, Xds)
        if settings.hessian is Hessian.AUTO:  # exact up to GRAM_EXACT_HESSIAN_MAX_PARAMETERS
            strategy = (Hessian.EXACT if layout.size <= GRAM_EXACT_HESSIAN_MAX_PARAMETERS
                        else Hessian.LIMITED_MEMORY)
    else:
        kernels = SumKernels(layout, settings.objective, margin, Xs, Xds, coef, norm,
                             compile=settings.compile, hessian=strategy is Hessian.EXACT,
                             threads=1 if settings.constrained else None,
                             blocked=not settings.constrained)
    return SEDSProblem(
        layout=layout, settings=settings, X=Xs, Xd=Xds, weights=w,
        position_scale=sx, velocity_scale=sv, target=demos.target.copy(), theta0=theta0,
        lbx=lbx, ubx=ubx, margin=margin, kernels=kernels,
        objective_function=kernels.casadi_function(), hessian=strategy, _memo=memo,
    )


#: ``hessian="auto"`` uses the exact Hessian up to this many parameters. Its per-sample C kernel grows as
#: P^2 (18k instructions at P = 49, 56k at P = 94, 1.4M at P = 424) and so does its compile time
#: (2 cores under load: 7 s at P = 49, 24-29 s at P = 75-79, 56 s at P = 94, 111 s at P = 119;
#: 3-D K = 15, P = 284, ran the compiler for over 8 minutes and 10 GB); above, IPOPT's L-BFGS
#: with exact gradients
EXACT_HESSIAN_MAX_PARAMETERS = 80


#: with the Gram statistics (``gmm="fixed"``, ``objective="mse"``) ``hessian="auto"`` is exact
#: up to this many parameters (2-D K <= 30, 3-D K <= 13), L-BFGS above: the Hessian's symbolic
#: expression is built by CasADi when IPOPT is set up, and in 7-D (49 parameters a component)
#: that took 11 s of a 15 s fit at K = 4 (the solve 2.4 s), growing to about 2 minutes at K = 8
GRAM_EXACT_HESSIAN_MAX_PARAMETERS = 120


def hessian_strategy(requested: Hessian | str, n_parameters: int) -> Hessian:
    """``Hessian.EXACT`` or ``Hessian.LIMITED_MEMORY`` for a request (``"auto"`` by problem
    size)."""
    requested = Hessian.parse(requested, "hessian")
    if requested is not Hessian.AUTO:
        return requested
    return (Hessian.EXACT if n_parameters <= EXACT_HESSIAN_MAX_PARAMETERS
            else Hessian.LIMITED_MEMORY)


def check_approach(demos: Demonstrations, X: np.ndarray, Xd: np.ndarray) -> None:
    """Refuse data a stable DS with this attractor cannot follow; warn about doubtful data.

    SEDS learns motions that converge to the target x*. A ``ValueError`` (before any solve) when
    the data clearly run away from x*: every demonstration ends farther from x* than it starts
    while the velocities point away from x* on average (for samples without time order: a mean
    cosine with x* - x below -0.5). Typical causes: demonstrations reversed in time, velocities
    with the wrong sign, or a wrong target. A :class:`~seds_casadi.ConvergenceWarning` when some
    demonstrations end more than half their start distance from x*, or the velocities point away
    from x* on average (a motion that first moves away, which SEDS's quadratic Lyapunov function
    cannot follow well).
    """
    from .errors import ConvergenceWarning

    r, v = np.linalg.norm(X, axis=1), np.linalg.norm(Xd, axis=1)
    ok = (r > 0) & (v > 0)
    mean_cos = float(np.mean(-np.sum(X[ok] * Xd[ok], axis=1) / (r[ok] * v[ok]))) if ok.any() \
        else 1.0
    ordered = demos.time_ordered
    start = [np.linalg.norm(p[0]) for p in demos.shifted_positions]
    end = [np.linalg.norm(p[-1]) for p in demos.shifted_positions]
    away = all(e >= s0 for s0, e in zip(start, end)) if ordered else mean_cos < -0.5
    problems = []
    if ordered:
        far = [n for n, (s0, e) in enumerate(zip(start, end)) if e > 0.5 * s0]
        if far:
            problems.append(f"demonstration(s) {far[:10]} end more than half their start "
                            "distance away from the target")
    if mean_cos < 0:
        problems.append(f"the velocities point away from the target on average (mean cosine "
                        f"with the direction to the target {mean_cos:.2f})")
    if mean_cos < 0 and away:
        raise ValueError(
            f"the demonstrations run away from the target {demos.target}: "
            + "; ".join(problems) + ". They may be reversed in time, their velocities may have "
            "the wrong sign, or the target is not where they end. A SEDS model always "
            "converges to its target.")
    if problems:
        warnings.warn("; ".join(problems) + f" (target {demos.target}); the model will still "
                      "converge to the target. Check the target (by default the mean end point) "
                      "or trim the demonstrations.", ConvergenceWarning, stacklevel=4)


def gmm_indices(layout: Layout) -> np.ndarray:
    """Indices in theta of the GMM over the positions: the priors (logits, or the raw priors
    of the constrained form), the means mu_k and the Cholesky factors of Sigma_x,k; with
    ``gmm="fixed"`` they keep their initial values and only the dynamics (A_k through B_k and
    W_k, or A_k and the velocity means of the constrained form; L_P; the noise of the
    likelihood objective) are optimised."""
    idx = list(range(layout.n_logits))
    for k in range(layout.K):
        s = layout.slices(k)
        for name in ("pi", "mu", "L"):
            if name in s:
                idx += range(s[name].start, s[name].stop)
    return np.array(sorted(idx), dtype=int)


def _bounds(layout: Layout, gain_limit: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Simple bounds on theta: means within +-50 (scaled units), exp-parametrised diagonals of
    the Cholesky factors within [1e-3, 1e2]; raw priors (constrained form) within [1e-8, 1]
    (Eq. 10d); L_P's log-diagonal within :data:`~seds_casadi.core.lyapunov.LYAPUNOV_DIAG_RANGE`
    and its off-diagonal within +-10, which bounds P's condition number. With ``gain_limit`` g:
    the entries of B_k within +-sqrt(g) and of W_k within +-g (constrained form: the entries of
    A_k within +-d g), which bounds the stiffness of every A_k."""
    lbx = np.full(layout.size, -np.inf)
    ubx = np.full(layout.size, np.inf)
    diag_pos = [i for i, (a, b) in enumerate(layout.tril) if a == b]
    for k in range(layout.K):
        s = layout.slices(k)
        lbx[s["mu"]], ubx[s["mu"]] = -50.0, 50.0
        if "pi" in s:
            lbx[s["pi"]], ubx[s["pi"]] = 1e-8, 1.0
        for name in ("L", "B", "Q"):
            if name in s:
                idx = np.arange(s[name].start, s[name].stop)[diag_pos]
                lbx[idx], ubx[idx] = np.log(1e-3), np.log(1e2)
    if gain_limit is not None:
        g = float(gain_limit)
        for k in range(layout.K):
            s = layout.slices(k)
            if "B" in s:
                idx = np.arange(s["B"].start, s["B"].stop)
                off = np.setdiff1d(idx, idx[diag_pos])
                lbx[off], ubx[off] = -np.sqrt(g), np.sqrt(g)
                ubx[idx[diag_pos]] = np.minimum(ubx[idx[diag_pos]], 0.5 * np.log(g))
                lbx[s["W"]], ubx[s["W"]] = -g, g
            else:
                lbx[s["A"]], ubx[s["A"]] = -layout.d * g, layout.d * g
    if layout.n_lyapunov:
        sl = layout.lyapunov_slice
        lbx[sl], ubx[sl] = -10.0, 10.0
        idx = np.arange(sl.start, sl.stop)[diag_pos]
        lbx[idx], ubx[idx] = np.log(LYAPUNOV_DIAG_RANGE[0]), np.log(LYAPUNOV_DIAG_RANGE[1])
    return lbx, ubx
