"""SEDS(init="lpv"): LPV-DS's initialisation (EM on the positions, least-squares stable gains)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from oracles import decaying_spiral_demos

from seds_casadi import SEDS
from seds_casadi.core.problem import _stable_gains_lpv


def _stable(rng, d, P):
    """A random A with A^T P + P A < 0: A = P^-1 (-(B B^T + I) + skew)."""
    B = rng.normal(size=(d, d))
    W = rng.normal(size=(d, d))
    return np.linalg.solve(P, -(B @ B.T + np.eye(d)) + (W - W.T))


@settings(max_examples=15, deadline=None, derandomize=True)
@given(seed=st.integers(0, 10_000), d=st.integers(2, 3), K=st.integers(1, 3))
def test_gains_recover_a_stable_mixture_exactly(seed, d, K):
    # data from K stable gains under a known soft mixing: the stage finds gains that reproduce
    # the velocities (the least-squares optimum is feasible) and each is stable for P
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(d, d))
    P = M @ M.T + d * np.eye(d)
    A = [_stable(rng, d, P) for _ in range(K)]
    X = rng.normal(size=(300, d))
    logits = rng.normal(size=(300, K))
    gamma = np.exp(logits) / np.exp(logits).sum(1, keepdims=True)
    Xd = np.einsum("nk,kij,nj->ni", gamma, np.array(A), X)
    start = [-np.eye(d) for _ in range(K)]
    got = _stable_gains_lpv(gamma, X, Xd, P, 1e-3, start)
    F = np.einsum("nk,kij,nj->ni", gamma, np.array(got), X)
    assert np.sqrt(np.mean((F - Xd) ** 2)) < 1e-3 * np.sqrt(np.mean(Xd ** 2))
    for Ak in got:
        assert np.linalg.eigvalsh(Ak.T @ P + P @ Ak).max() < -1e-3


def test_gains_respect_stability_when_the_data_do_not():
    # an unstable linear system: the best stable gain, not the data's
    rng = np.random.default_rng(0)
    X = rng.normal(size=(200, 2))
    A_true = np.array([[0.5, 1.0], [-1.0, 0.2]])  # expanding spiral
    got = _stable_gains_lpv(np.ones((200, 1)), X, X @ A_true.T, np.eye(2), 1e-3,
                            [-np.eye(2)])[0]
    assert np.linalg.eigvalsh(got + got.T).max() <= -2e-3 + 1e-9
    # the rotation is kept (the skew part is free): same sign as the data's
    assert got[0, 1] - got[1, 0] == pytest.approx(2.0, rel=0.05)


_spiral_demos = decaying_spiral_demos


@pytest.mark.parametrize("lyapunov", ["identity", "learned"])
def test_lpv_init_fits_a_certified_model(lyapunov):
    demos = _spiral_demos()
    joint = SEDS(3, objective="mse", random_state=0, lyapunov=lyapunov).fit(demos).model_
    lpv = SEDS(3, objective="mse", random_state=0, lyapunov=lyapunov,
               init="lpv").fit(demos).model_
    for m in (joint, lpv):
        c = m.certificate
        assert c["max_eig_lyapunov"] < 0 and c["min_eig_cov"] > 0
    # the LPV start is already a good model: IPOPT starts lower than from the joint EM
    assert lpv.fit_info["objective_initial"] <= joint.fit_info["objective_initial"] + 1e-12
    assert lpv.fit_info["objective"] <= 1.05 * joint.fit_info["objective"] + 1e-3


def test_unknown_init_is_refused():
    with pytest.raises(ValueError, match="'init' parameter of SEDS must be a str among "
                                         "{'joint-em', 'lpv', 'pc', 'auto'}. Got 'kmeans'"):
        SEDS(2, init="kmeans").fit(_spiral_demos())
