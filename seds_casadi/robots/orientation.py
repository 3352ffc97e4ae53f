"""The club head's orientation: the face orientation the controller asks for, and the
orientation error it corrects (by the controller every tick, by the start placement's IK).

Each is written once, as a CasADi expression (:func:`face_orientation_sx`,
:func:`orientation_error_sx`, with the rotation vector of :func:`log3_sx`): the compiled 500 Hz
tick inlines them, and :func:`face_orientation` / :func:`orientation_error` evaluate them
numerically. A numpy version of the rotation vector is kept in the tests as an oracle.
"""

from __future__ import annotations

import functools

import casadi as ca
import numpy as np

__all__ = ["log3_sx", "orientation_error_sx", "face_orientation_sx", "orientation_error",
           "face_orientation", "orientation_error_function"]

#: near these angles [rad] the rotation vector is read from its limits (0: the skew part; pi: the
#: diagonal), where theta / sin(theta) loses precision
_SMALL, _NEAR_PI = 1e-6, np.pi - 1e-4


def _vee_skew(M):
    """(M - M^T) as a vector: (M21 - M12, M02 - M20, M10 - M01)."""
    return ca.vertcat(M[2, 1] - M[1, 2], M[0, 2] - M[2, 0], M[1, 0] - M[0, 1])


def _axis_near_pi(R, theta):
    """theta * axis of a rotation R by about pi: the axis from R's diagonal, |a_k| =
    sqrt((R_kk + 1) / 2) for the largest, the others a_j = R_kj / (2 a_k)."""
    a = [ca.sqrt(ca.fmax((R[k, k] + 1) / 2, 0)) for k in range(3)]
    candidates = []
    for k in range(3):
        ax = [R[k, j] / (2 * ca.fmax(a[k], 1e-12)) if j != k else a[k] for j in range(3)]
        v = ca.vertcat(*ax)
        candidates.append(theta * v / ca.fmax(ca.norm_2(v), 1e-12))
    # the first largest diagonal term, as numpy's argmax picks it
    first = ca.logic_and(a[0] >= a[1], a[0] >= a[2])
    return ca.if_else(first, candidates[0], ca.if_else(a[1] >= a[2], candidates[1],
                                                       candidates[2]))


def log3_sx(R) -> ca.SX:
    """The rotation vector theta * axis of a rotation matrix R (the log of SO(3)), as SX.

    theta = arccos((tr R - 1) / 2); the vector is theta / (2 sin theta) (R - R^T)^vee, read
    from the skew part below 1e-6 rad and from the diagonal within 1e-4 rad of pi.

    Parameters
    ----------
    R : casadi.SX, shape (3, 3)

    Returns
    -------
    casadi.SX, shape (3, 1)
    """
    c = ca.fmin(ca.fmax((ca.trace(R) - 1) / 2, -1.0), 1.0)
    theta = ca.acos(c)
    w = _vee_skew(R)
    generic = theta / (2 * ca.fmax(ca.sin(theta), 1e-12)) * w
    return ca.if_else(theta < _SMALL, 0.5 * w,
                      ca.if_else(theta > _NEAR_PI, _axis_near_pi(R, theta), generic))


def orientation_error_sx(R, Rd, full: bool) -> ca.SX:
    """Rotation vector from R towards Rd, as SX: all three axes (``full``: log(Rd R^T)), or,
    for arms with fewer than six joints, which cannot also hold the shaft, only the turn about
    the vertical that brings the horizontal part of the face's normal (x axis) onto Rd's (the
    direction the ball leaves in; the face may tilt).

    Parameters
    ----------
    R, Rd : casadi.SX, shape (3, 3)
        The club head's rotation and the desired one, in the same frame.
    full : bool
    """
    if full:
        return log3_sx(Rd @ R.T)
    # the turn about the vertical from the normal's horizontal part to the desired one's: the
    # ball leaves along the horizontal part of the normal, whatever its tilt
    n, d = R[:, 0], Rd[:, 0]
    turn = ca.atan2(n[0] * d[1] - n[1] * d[0], n[0] * d[0] + n[1] * d[1])
    return ca.vertcat(0, 0, turn)


def face_orientation_sx(direction) -> ca.SX:
    """The desired club-head rotation, as SX (3, 3): x (the face's normal) along the horizontal
    part of ``direction`` (+x if that is shorter than 1e-9), z (the shaft, towards the flange)
    up, y = z cross x."""
    d = ca.vertcat(direction[0], direction[1], 0)
    n = ca.norm_2(d)
    x = ca.if_else(n > 1e-9, d / ca.fmax(n, 1e-9), ca.DM([1.0, 0.0, 0.0]))
    z = ca.DM([0.0, 0.0, 1.0])
    return ca.horzcat(x, ca.cross(z, x), z)


@functools.lru_cache(maxsize=2)
def orientation_error_function(full: bool) -> ca.Function:
    """:func:`orientation_error_sx` as a Function (R (3, 3), Rd (3, 3)) -> e (3,)."""
    R, Rd = ca.SX.sym("R", 3, 3), ca.SX.sym("Rd", 3, 3)
    return ca.Function("orientation_error", [R, Rd], [orientation_error_sx(R, Rd, full)],
                       ["R", "Rd"], ["e"])


@functools.lru_cache(maxsize=1)
def _face_function() -> ca.Function:
    d = ca.SX.sym("direction", 3)
    return ca.Function("face_orientation", [d], [face_orientation_sx(d)], ["direction"], ["R"])


def orientation_error(R: np.ndarray, Rd: np.ndarray, full: bool) -> np.ndarray:
    """Rotation vector from R towards Rd (:func:`orientation_error_sx`), shape (3,)."""
    out = orientation_error_function(bool(full))(np.asarray(R, float), np.asarray(Rd, float))
    return np.asarray(out, dtype=float).ravel()


def face_orientation(direction) -> np.ndarray:
    """Desired club-head rotation (:func:`face_orientation_sx`), shape (3, 3): x (face normal)
    along the horizontal part of ``direction``, z (shaft, towards the flange) up."""
    d = np.asarray(direction, float).ravel()
    if d.shape != (3,):
        raise ValueError(f"direction must be a 3-vector, got shape {np.shape(direction)}")
    return np.asarray(_face_function()(d), dtype=float)
