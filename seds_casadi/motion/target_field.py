"""The target field h(x) = f(x) / ||f(x)|| of a certified SEDS model (paper Eq. 8) and its limit
psi* at the target (Eq. 13).

Eq. 8 is written once, as a CasADi expression (:func:`target_field_sx`); :class:`TargetField`
evaluates it numerically (:func:`seds_casadi.codegen.batch_evaluate`, a map over many points) and
:mod:`seds_casadi.motion.hitting` builds Eq. 14 on it. A numpy version is kept in the tests as an
oracle.

The limit at the target: near x* the SEDS model is linear, f(x) ~ J (x - x*) with
J = sum_k h^k(x*) A_k, and every trajectory that is not exceptional arrives tangent to the
eigenvector of J with the slowest (real) eigenvalue. psi* is that eigenvector, oriented along the
demonstrations' arrival. A model whose slowest eigenvalues are a complex pair spirals into x*, has
no limit direction, and is refused (ValueError).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from ..codegen import batch_evaluate
from ..core.gmm import responsibilities
from ..core.stable_ds import StableDS
from ..core.strength import as_points

__all__ = ["TargetField", "target_field_sx", "certified_velocity_sx", "limit_direction"]

#: below this norm of f the target field takes its limit psi* (only at x* itself, in practice)
TINY = 1e-200


def certified_velocity_sx(y, ds: StableDS) -> ca.SX:
    """f(y) = sum_k h^k(y) A_k (y - x*) of a certified model (Eq. 5).

    :meth:`StableDS.gains_velocity_sx`: a model's strength factor, if it has one, is left out
    (it is a positive factor, which Eq. 8 normalises away).

    Parameters
    ----------
    y : casadi.SX, shape (d, 1)
    ds : StableDS
    """
    return ds.gains_velocity_sx(y)


def target_field_sx(y, ds: StableDS, hitting_direction) -> tuple[ca.SX, ca.SX]:
    """Eq. 8 as SX: h(y) = f(y) / ||f(y)||, and psi* where ||f(y)|| <= 1e-200 (at x*).

    Parameters
    ----------
    y : casadi.SX, shape (d, 1)
    ds : StableDS
        Certified (f vanishes only at x*).
    hitting_direction : array, shape (d,)
        psi*, the limit of h at x* (Eq. 13; :func:`limit_direction`).

    Returns
    -------
    h, f : casadi.SX, shape (d, 1)
        The target field and the velocity it normalises (:func:`certified_velocity_sx`).
    """
    f = certified_velocity_sx(y, ds)
    # ||f||^2 overflows from |f| ~ 1e154 (far from the data): normalise by max |f_i| first there
    big = ca.mmax(ca.fabs(f))
    g = ca.if_else(big > 1e100, f / ca.fmax(big, 1e100), f)
    ng = ca.norm_2(g)
    h = ca.if_else(ng > TINY, g / ca.fmax(ng, TINY), ca.DM(np.asarray(hitting_direction, float)))
    return h, f


def limit_direction(ds: StableDS, approach=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """psi* = lim_{x -> x*} h(x) (Eq. 13): the slowest eigenvector of J = df/dx at x*.

    Parameters
    ----------
    ds : StableDS
    approach : array, shape (d,), optional
        Orients psi* (psi* . approach >= 0). Default: +x.

    Returns
    -------
    hitting_direction : array, shape (d,)
        psi*, unit norm.
    jacobian : array, shape (d, d)
        J = sum_k h^k(x*) A_k.
    eigenvalues : array, shape (d,)
        Of J (complex).

    Raises
    ------
    ValueError
        The slowest eigenvalues are a complex pair: the model spirals into x* and h has no limit.
    """
    d = ds.n_dims
    w = responsibilities(ds.target[None], ds.priors, ds.means[:, :d], ds.covariances[:, :d, :d])[0]
    J = np.einsum("k,kij->ij", w, ds.A)
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
    return psi, J, ev


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
    eigenvalues : array, shape (d,)
        Of J.
    """

    def __init__(self, ds: StableDS, approach=None) -> None:
        if not isinstance(ds, StableDS):
            raise TypeError(f"TargetField needs a StableDS, got {type(ds).__name__}")
        self.ds = ds
        psi, J, ev = limit_direction(ds, approach)
        self.approach = np.eye(ds.n_dims)[0] if approach is None else np.asarray(approach, float)
        self.jacobian = J
        self.hitting_direction = psi
        self.eigenvalues = ev

    def sx(self, y) -> ca.SX:
        """h(y) of Eq. 8 as SX (:func:`target_field_sx`), for building larger expressions."""
        return target_field_sx(y, self.ds, self.hitting_direction)[0]

    def to_casadi(self, name: str = "target_field") -> ca.Function:
        """Eq. 8 as a CasADi Function x (d,) -> (h (d,), f (d,))."""
        y = ca.SX.sym("x", self.ds.n_dims)
        h, f = target_field_sx(y, self.ds, self.hitting_direction)
        return ca.Function(name, [y], [h, f], ["x"], ["h", "f"])

    def _evaluate(self, X, output: int) -> np.ndarray:
        X2, single = as_points(X, self.ds.n_dims)
        if len(X2) == 0:
            return X2.copy()
        f = self.__dict__.get("_f")
        if f is None:
            f = self.__dict__["_f"] = self.to_casadi()
        out = batch_evaluate(f, X2.T)[output]
        return out[0] if single else out

    def __getstate__(self) -> dict:  # the cached CasADi Function is rebuilt after unpickling
        state = dict(self.__dict__)
        state.pop("_f", None)
        return state

    def velocity(self, X) -> np.ndarray:
        """f(x) = sum_k h^k(x) A_k (x - x*) at points X, shape (n, d) or (d,): Eq. 5 for a
        certified model, in the form without cancellation near x* (:func:`certified_velocity_sx`)."""
        return self._evaluate(X, 1)

    def __call__(self, X) -> np.ndarray:
        """h at points X, shape (n, d) or (d,), in the ds's coordinates; psi* at x* (Eq. 8)."""
        return self._evaluate(X, 0)
