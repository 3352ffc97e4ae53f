"""Self-correction: a robot that learns from its own shots when the real green (the *world*)
differs from the field it was taught on (beyond the paper; its Section 7.2.2 names the causes:
a green slower or faster than its model, a tilted table, a contact that is not the impact
model).

The robot is taught on the nominal field (Section 5: the teacher's good shots, then GPR or
GMR, Eq. 17-18). On the world it observes of each shot only what a camera would give
(:class:`Observation`): the ball's path with its time stamps, where it stopped, whether it
sank. With a budget of ``N`` shots (:func:`adapt`):

1. **Where to shoot** (:func:`next_situation`): the declared situation farthest from every
   situation already played (greedy maximin over candidates drawn from the field's
   declaration, in situation coordinates scaled by their spread; the first at the centre).
   With a stationary kernel the correction's posterior variance depends only on these
   distances, so this is where the correction is least known, without trusting
   hyperparameters fitted on a handful of shots.
2. **The green, estimated** (:class:`Green`, :func:`estimate_green`): the rolling
   resistance's factor, a tilt, the launch speed's factor and its angle
   (:data:`GREEN_PARAMETERS`) that make the nominal ball model, with the robot's measured
   launch (:class:`~seds_casadi.minigolf.stroke.LaunchTable`), reproduce the observed paths;
   least squares, regularised towards the nominal green (:data:`GREEN_PRIOR`).
3. **What the green model still gets wrong** (:class:`PassageResidual`): the observed balls'
   passage of the hole (:func:`path_passage`: the side distance and the squared speed where
   the path passes nearest to the hole) less the estimated green's for the same hits, learned
   over the situations by GPR (Eq. 17). Near zero on a world the five parameters describe.
4. **How it plays** (:func:`matching_shots`): the taught shot moved onto the estimated green
   by Newton's method on (alpha, log kappa), until its ball passes the hole as the taught
   shot's ball passes it on the nominal green (less the residual). A shot that sinks on the
   nominal green then sinks on the world; on a green equal to the nominal nothing changes.
5. **What it learns** (:class:`CorrectedModel`): the taught model plus a correction in
   (alpha [deg], log kappa), learned by GPR from the teacher's shots at 24 of the data set's
   situations moved onto the estimated green, less the taught model's predictions there. A
   speed gain that the teacher held fixed (``fixed_speed``) is corrected as well.

:func:`adapt` runs the loop; ``seds-casadi play --world WORLD --adapt N`` uses it
(:mod:`seds_casadi.app.play`).
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass, field, replace

import numpy as np

from ..minigolf.ball import simulate_shots, substeps
from ..minigolf.fields import FIELDS_FOLDER, Field, load_field
from ..minigolf.hitting_data import HittingDataset
from ..minigolf.parameters import GPRModel
from ..minigolf.stroke import LaunchTable, Stroke
from .scene import Scene
from .shot import ENGINES, Shot, ShotResult, play_shot

__all__ = ["World", "check_world", "Green", "Observation", "estimate_green", "CorrectedModel",
           "Adaptation", "AdaptationStep", "adapt", "next_situation", "GREEN_PARAMETERS",
           "PassageResidual", "hole_passage", "path_passage", "matching_shots",
           "launch_limited", "fastest_launch", "launch_ceiling",
           "world_names"]

#: what a world may change of its field (the green); everything else is the course
_GREEN = ("name", "surface", "stimp", "rolling_resistance", "wall_restitution", "teacher")


@dataclass(frozen=True)
class World:
    """Where the shots are really played: a green that may differ from the robot's model.

    Attributes
    ----------
    field : Field
        The world's field (the same course as the nominal field: bounds, walls, hole and
        situations; the green may differ).
    engine : {"ball", "exudyn"}
        The ball model after the arm's simulated swing, or exudyn's multibody model of arm,
        club and ball with contact (:func:`~seds_casadi.game.shot.play_shot`).
    label : str
        How the world is named in outputs.
    """

    field: Field
    engine: str = "ball"
    label: str = ""

    def __post_init__(self) -> None:
        if self.engine not in ENGINES:
            raise ValueError(f"unknown engine {self.engine!r}; choose one of "
                             f"{', '.join(ENGINES)}")
        if not self.label:
            object.__setattr__(self, "label", self.field.name if self.engine == "ball"
                               else f"{self.field.name} in exudyn")

    @classmethod
    def load(cls, world: str | None, nominal: Field) -> World:
        """The world named on the command line: None (the nominal field itself), ``"exudyn"``
        (the nominal field in exudyn's multibody model) or a field name or ``.json`` file,
        checked to be the same course (:func:`check_world`)."""
        if world is None:
            return cls(nominal, "ball", nominal.name)
        if str(world) == "exudyn":
            return cls(nominal, "exudyn")
        name = str(world)
        if name in world_names():
            name = os.path.join(FIELDS_FOLDER, "worlds", name + ".json")
        fld = load_field(name)
        check_world(fld, nominal)
        return cls(fld, "ball")


def world_names() -> list[str]:
    """Names of the worlds shipped with the package (``fields/worlds/``): shipped fields with
    another green, for ``play --world``."""
    folder = os.path.join(FIELDS_FOLDER, "worlds")
    if not os.path.isdir(folder):
        return []
    return sorted(f[:-5] for f in os.listdir(folder) if f.endswith(".json"))


def _plain(v):
    """Numbers and lists of a field specification as plain Python values (for messages)."""
    if isinstance(v, dict):
        return {k: _plain(x) for k, x in v.items()}
    if isinstance(v, (list, tuple, np.ndarray)):
        return [_plain(x) for x in v]
    if isinstance(v, (float, np.floating)):
        return float(v)
    return v


def check_world(world: Field, nominal: Field) -> None:
    """Refuse a world that is another course than the nominal field.

    A world may differ from the field only in its green (surface, stimp or rolling
    resistance, wall restitution): the robot cannot play a course whose bounds, walls, hole or
    situations differ from those it was taught on. ``ValueError`` names the first difference.
    """
    checks = [("bounds", world.bounds.tolist(), nominal.bounds.tolist()),
              ("boundary", world.boundary, nominal.boundary),
              ("hole", [*world.hole.tolist(), world.hole_radius],
               [*nominal.hole.tolist(), nominal.hole_radius]),
              ("ball_region", world.ball_region.tolist(), nominal.ball_region.tolist()),
              ("situations", _plain(world.situations.to_spec()),
               _plain(nominal.situations.to_spec()))]
    for what, w, n in checks:
        if w != n:
            raise ValueError(f"the world {world.name!r} is another course than the field "
                             f"{nominal.name!r}: its {what} {w} differ from {n}; a world may "
                             f"differ only in its green ({', '.join(_GREEN[1:5])})")


class TiltedSurface:
    """A surface tilted by a plane: H(p) + t . p (the green's tilt the robot estimates).

    Delegates everything else to the surface it tilts; the ball model's numpy engine reads
    it (:func:`~seds_casadi.minigolf.ball.simulate_shots` with ``engine="numpy"``).
    """

    def __init__(self, base, tilt) -> None:
        self.base = base
        self.tilt = np.asarray(tilt, float).reshape(2)

    def __getattr__(self, name):
        return getattr(self.base, name)

    def height(self, P) -> np.ndarray:
        P = np.atleast_2d(P)
        return self.base.height(P) + P @ self.tilt

    def gradient(self, P) -> np.ndarray:
        return self.base.gradient(P) + self.tilt

    def extremes(self, bounds, spacing: float = 0.01) -> dict:
        e = dict(self.base.extremes(bounds, spacing))
        b = np.asarray(bounds, float)
        e["slope"] = e["slope"] + float(np.linalg.norm(self.tilt))
        e["height_range"] = e["height_range"] + float(
            abs(self.tilt[0]) * (b[1] - b[0]) + abs(self.tilt[1]) * (b[3] - b[2]))
        return e


@dataclass(frozen=True)
class Observation:
    """What the robot sees of a shot on the world (a camera): the ball's path with its times,
    where it stopped, whether it sank, and the hit it played.

    Attributes
    ----------
    ball : array (2,)
    alpha, kappa : float
        The hit played (alpha [rad]).
    times : array (k,)
        Seconds from the launch (the ball's first movement).
    path : array (k, 2)
    final : array (2,)
    sunk : bool
    """

    ball: np.ndarray
    alpha: float
    kappa: float
    times: np.ndarray
    path: np.ndarray
    final: np.ndarray
    sunk: bool

    @classmethod
    def from_result(cls, res: ShotResult) -> Observation | None:
        """The observation of a played shot (None when the club did not hit the ball)."""
        if not res.hit or res.path is None or len(res.path) < 3:
            return None
        P = np.asarray(res.path, float)
        T = (np.asarray(res.path_time, float) if res.path_time is not None
             else np.arange(len(P)) * 0.01)
        # the launch: the first movement, back-extrapolated from the first moving step
        moved = np.flatnonzero(np.linalg.norm(P - P[0], axis=1) > 1e-3)
        if moved.size == 0:
            return None
        j = int(moved[0])
        step = max(float(np.linalg.norm(P[j] - P[j - 1])) if j > 0 else 0.0, 1e-9)
        t0 = T[j] - float(np.linalg.norm(P[j] - P[0])) / step * (T[j] - T[max(j - 1, 0)])
        keep = slice(max(j - 1, 0), None)
        return cls(np.asarray(res.shot.ball, float), res.shot.alpha, res.shot.kappa,
                   T[keep] - t0, P[keep], np.asarray(res.final_position, float), res.sunk)


#: the green's parameters the robot estimates (:class:`Green`): log of the rolling resistance's
#: factor, the tilt (dH/dx, dH/dy), log of the launch speed's factor, the launch's angle offset
#: [rad]; and the prior spread of each (how far the world is expected from its model)
GREEN_PARAMETERS = ("log_rolling_resistance", "tilt_x", "tilt_y", "log_launch_speed",
                    "launch_angle")
GREEN_PRIOR = np.array([0.5, 0.01, 0.01, 0.2, np.deg2rad(3.0)])
#: the camera's position noise assumed by the fit [m]
CAMERA_SIGMA = 0.01
#: where the fit's loss turns from squares to absolute values (soft L1), in camera sigmas: a
#: path the green's parameters cannot explain (a bump, a launch the table misses near the
#: arm's speed limit) pulls the estimate linearly, not quadratically
ROBUST_SCALE = 3.0


@dataclass(frozen=True)
class Green:
    """The robot's model of the world's green: the nominal field and the robot's launch,
    changed by the estimated parameters q (:data:`GREEN_PARAMETERS`; zeros: the nominal).

    The rolling resistance is rho exp(q0), the surface is tilted by (q1, q2), the launch is
    exp(q3) faster and turned by q4 (the robot's :class:`~seds_casadi.minigolf.stroke.LaunchTable`
    changed so).
    """

    nominal: Field
    stroke: Stroke
    q: np.ndarray = field(default_factory=lambda: np.zeros(len(GREEN_PARAMETERS)))

    def __post_init__(self) -> None:
        object.__setattr__(self, "q", np.asarray(self.q, float).reshape(len(GREEN_PARAMETERS)))
        if self.stroke.launch_table is None:
            raise ValueError("the robot's launch must be measured first "
                             "(seds_casadi.game.calibrate_launch)")

    @property
    def field(self) -> Field:
        """The estimated field (its ball model runs on the numpy engine)."""
        q = self.q
        return replace(self.nominal, name=f"{self.nominal.name} (estimated)",
                       surface=TiltedSurface(self.nominal.surface, q[1:3]),
                       rolling_resistance=self.nominal.rolling_resistance * float(np.exp(q[0])))

    @property
    def launch_stroke(self) -> Stroke:
        """The robot's stroke with the estimated launch."""
        t = self.stroke.launch_table
        table = LaunchTable(t.alphas, t.kappas, t.speed_factor * float(np.exp(self.q[3])),
                            t.angle_offset + self.q[4], t.robot)
        return self.stroke.with_launch(table)

    def describe(self) -> str:
        """The estimate in words."""
        q = self.q
        return (f"rolling resistance x{np.exp(q[0]):.2f}, tilt ({100 * q[1]:+.2f} %, "
                f"{100 * q[2]:+.2f} %), launch x{np.exp(q[3]):.3f} turned "
                f"{np.rad2deg(q[4]):+.2f} deg")

    def simulate(self, balls, alphas, kappas, hole_free: bool = True):
        """The estimated green's ball model for hits (alpha [rad], kappa) from ``balls``
        (n, 2), with paths (numpy engine); ``hole_free``: a hole too small to catch a ball."""
        fld = self.field
        if hole_free:
            fld = replace(fld, hole_radius=1e-6)
        V = self.launch_stroke.launch_velocity(alphas, kappas)
        return simulate_shots(fld, np.asarray(balls, float), V, dt=0.01, engine="numpy",
                              record_paths=True), 0.01 / substeps(fld, V, 0.01)

    def end_points(self, balls, alphas, kappas) -> np.ndarray:
        """Where the hits (alpha [rad], kappa) from ``balls`` (n, 2) end on this green, the hole
        left out, shape (n, 2)."""
        fld = replace(self.field, hole_radius=1e-6)
        V = self.launch_stroke.launch_velocity(alphas, kappas)
        return simulate_shots(fld, np.asarray(balls, float), V, dt=0.01,
                              engine="numpy").final_position

    def residuals(self, observations: list[Observation], every: float = 0.1) -> np.ndarray:
        """Differences between the observed paths (at ``every`` seconds and at their ends) and
        the estimated green's, over :data:`CAMERA_SIGMA`, and the prior's terms."""
        B = np.array([o.ball for o in observations])
        res, dt = self.simulate(B, np.array([o.alpha for o in observations]),
                                np.array([o.kappa for o in observations]))
        out = []
        for o, path in zip(observations, res.paths):
            tm = np.arange(len(path)) * dt
            ts = np.append(np.arange(0.0, o.times[-1], every), o.times[-1])
            obs = np.column_stack([np.interp(ts, o.times, o.path[:, j]) for j in range(2)])
            mod = np.column_stack([np.interp(ts, tm, path[:, j]) for j in range(2)])
            out.append(((mod - obs) / CAMERA_SIGMA).ravel())
            if not o.sunk:   # where it stopped, at whatever time the model stops
                out.append((path[-1] - o.final) / CAMERA_SIGMA)
        out.append(self.q / GREEN_PRIOR)
        return np.concatenate(out)


def estimate_green(green: Green, observations: list[Observation], last: int = 10) -> Green:
    """The green's parameters that best explain the observed paths (least squares over the
    ``last`` observations, from the current estimate, regularised towards the nominal field by
    :data:`GREEN_PRIOR`)."""
    from scipy.optimize import least_squares

    obs = [o for o in observations if o is not None][-int(last):]
    if not obs:
        return green
    scale = GREEN_PRIOR

    def fun(z):
        r = Green(green.nominal, green.stroke, z * scale).residuals(obs)
        # soft L1 on the paths' terms (as a residual: rho(r) = r'^2), squares on the prior's
        c = ROBUST_SCALE
        m = len(r) - len(GREEN_PARAMETERS)
        r[:m] = np.sign(r[:m]) * c * np.sqrt(2 * (np.sqrt(1 + (r[:m] / c) ** 2) - 1))
        return r

    # from the last estimate and, unless that fits the paths within the camera's noise, from
    # the nominal green too: a tilt along the line of play and a rolling resistance both slow
    # the ball down, and a first estimate can take the one for the other; the better fit of
    # the two is kept
    best = None
    for start in (green.q / scale, np.zeros_like(green.q)):
        sol = least_squares(fun, start, method="trf", diff_step=1e-3, x_scale=1.0,
                            max_nfev=20, xtol=1e-3, ftol=1e-3)
        if best is None or sol.cost < best.cost:
            best = sol
        if not np.any(green.q) or 2 * best.cost / len(best.fun) < 4.0:
            break
    sol = best
    return Green(green.nominal, green.stroke, sol.x * scale)

class CorrectedModel:
    """A taught hitting-parameter model plus a learned correction (module docstring, step 3).

    Parameters
    ----------
    base : fitted GPRModel or GMRModel
        The taught model: s = hole - ball -> alpha [deg] (and kappa).
    fixed_kappa : float or None
        The teacher's fixed speed gain when ``base`` predicts the angle only.
    random_state : int
        Of the correction's GPR.

    Attributes
    ----------
    S_, D_ : arrays, shapes (m, 2)
        Situations of the adaptation shots and the corrections they imply (alpha [deg],
        log kappa).
    limited_ : (int, int, int)
        Of the situations the correction was learned at, how many the arm's launch cannot
        serve on the estimated green (:func:`launch_limited`), how many there were, and how
        many of the first stop short of the hole's edge even at the arm's fastest hit.
    """

    def __init__(self, base, fixed_kappa: float | None = None, random_state: int = 0) -> None:
        self.base = base
        self.fixed_kappa = fixed_kappa
        self.random_state = random_state
        self.S_ = np.zeros((0, 2))
        self.D_ = np.zeros((0, 2))
        self.limited_ = (0, 0, 0)
        self._gp: GPRModel | None = None

    def taught(self, S) -> np.ndarray:
        """The taught model's (alpha [deg], kappa), shape (n, 2)."""
        S = np.atleast_2d(np.asarray(S, float))
        pred = np.asarray(self.base.predict(S), float).reshape(len(S), -1)
        if pred.shape[1] > 1:
            return pred[:, :2]
        if self.fixed_kappa is None:
            raise ValueError("the model predicts the angle only: give its fixed_kappa")
        return np.column_stack([pred[:, 0], np.full(len(S), float(self.fixed_kappa))])

    def fit_correction(self, S, D) -> CorrectedModel:
        """Learn the correction from situations S (m, 2) and their corrections D (m, 2):
        alpha [deg] and log kappa; returns self."""
        S = np.atleast_2d(np.asarray(S, float))
        D = np.atleast_2d(np.asarray(D, float))
        if S.shape != D.shape or S.shape[1] != 2 or not np.all(np.isfinite(D)):
            raise ValueError(f"S and D must be finite, shapes (m, 2); got {S.shape}, {D.shape}")
        self.S_, self.D_ = S, D
        self._gp = None
        distinct = len(np.unique(np.round(S, 9), axis=0))
        if distinct >= 2:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                self._gp = GPRModel(n_restarts=2, random_state=self.random_state).fit(S, D)
        return self

    def correction(self, S) -> np.ndarray:
        """The learned correction (n, 2): alpha [deg] and log kappa (zero before any shot)."""
        S = np.atleast_2d(np.asarray(S, float))
        if len(self.D_) == 0:
            return np.zeros((len(S), 2))
        if self._gp is None:
            return np.tile(self.D_.mean(axis=0), (len(S), 1))
        return self._gp.predict(S)

    def predict(self, S) -> np.ndarray:
        """Corrected (alpha [deg], kappa), shape (n, 2)."""
        T = self.taught(S)
        C = self.correction(S)
        return np.column_stack([T[:, 0] + C[:, 0], T[:, 1] * np.exp(C[:, 1])])


@dataclass
class AdaptationStep:
    """One shot of the budget: what was played and observed, and the green estimated after it.

    Attributes
    ----------
    result : ShotResult
        The shot on the world (the robot uses only what :class:`Observation` keeps of it).
    green : array (5,)
        The green's parameters estimated after this shot (:data:`GREEN_PARAMETERS`).
    miss_distance : float
        From the ball's end to the hole [m] (0 when sunk).
    """

    result: ShotResult
    green: np.ndarray
    miss_distance: float


@dataclass
class Adaptation:
    """The outcome of :func:`adapt`: the corrected model, the estimated green, the shots, and
    the corrected models after the numbers of shots asked for (``snapshots``: shots -> model;
    0: the taught model)."""

    model: CorrectedModel
    world: World
    green: Green | None = None
    steps: list[AdaptationStep] = field(default_factory=list)
    residual: PassageResidual | None = None
    snapshots: dict = field(default_factory=dict)

    @property
    def sunk(self) -> np.ndarray:
        """Whether each adaptation shot sank."""
        return np.array([s.result.sunk for s in self.steps], bool)

    @property
    def miss_distance(self) -> np.ndarray:
        """Each adaptation shot's distance from the hole [m] (0: sunk)."""
        return np.array([s.miss_distance for s in self.steps])


def next_situation(candidates: tuple[np.ndarray, np.ndarray], played: np.ndarray,
                   scale: np.ndarray) -> int:
    """Index of the candidate situation (balls, holes) to play next (module docstring, step
    1): the centre of the candidates first, then the farthest from every situation played
    (s = hole - ball, scaled by ``scale``)."""
    balls, holes = candidates
    S = (holes - balls) / scale
    if len(played) == 0:
        return int(np.argmin(np.sum((S - np.median(S, axis=0)) ** 2, axis=1)))
    P = np.atleast_2d(played) / scale
    d = np.min(np.sum((S[:, None, :] - P[None, :, :]) ** 2, axis=2), axis=1)
    return int(np.argmax(d))


def path_passage(path, times, hole, a_roll: float) -> np.ndarray:
    """How a path (k, 2) with its times (k,) passes the hole: (signed distance from the hole's
    centre to the path where it passes nearest [m], positive with the hole on the path's left;
    the squared speed there [m^2/s^2], or for a ball that stops short of the hole minus
    2 a_roll d, d its distance short: the squared speed it lacked; the side distance then from
    where it stopped to the line from its start to the hole). Continuous in the hit (up to
    the small step where a ball stops abreast of the hole), so Newton's method can steer it
    (:func:`matching_shots`)."""
    path = np.asarray(path, float)
    h = np.asarray(hole, float)
    if len(path) < 2:
        return np.array([0.0, -2 * a_roll * float(np.linalg.norm(h - path[0]))])
    seg = np.diff(path, axis=0)
    dt = np.maximum(np.diff(np.asarray(times, float)), 1e-9)
    L2 = np.maximum(np.sum(seg * seg, axis=1), 1e-18)
    lam = np.clip(np.sum((h - path[:-1]) * seg, axis=1) / L2, 0.0, 1.0)
    near = path[:-1] + lam[:, None] * seg
    j = int(np.argmin(np.sum((near - h) ** 2, axis=1)))
    u = seg[j] / np.sqrt(L2[j])
    d = h - near[j]
    offset = float(u[0] * d[1] - u[1] * d[0])
    if j == len(seg) - 1:   # nearest where it stopped: short of the hole, or abreast of it
        # measured against the line from the start to the hole: a slow ball's last heading
        # wanders on an uneven green, where it stopped does not
        line = h - path[0]
        ul = line / max(float(np.linalg.norm(line)), 1e-12)
        de = h - path[-1]
        ahead = float(de @ ul)
        if ahead > 1e-9:
            return np.array([float(ul[0] * de[1] - ul[1] * de[0]), -2 * a_roll * ahead])
    return np.array([offset, L2[j] / dt[j] ** 2])


def hole_passage(green: Green, balls, holes, alphas, kappas) -> np.ndarray:
    """How the hits' balls pass their holes on a green (the hole left out), shape (n, 2)
    (:func:`path_passage`)."""
    holes = np.atleast_2d(np.asarray(holes, float))
    res, dt = green.simulate(balls, alphas, kappas)
    a_roll = 5 / 7 * green.field.rolling_resistance * 9.81
    return np.array([path_passage(path, np.arange(len(path)) * dt, h, a_roll)
                     for path, h in zip(res.paths, holes)])


#: the least noise the passage residual's GP assumes (side distance [m], squared speed
#: [m^2/s^2]): the camera's and the green's small-scale unevenness (a bump, a seam), which no
#: smooth correction can predict and which the GP must not interpolate
RESIDUAL_NOISE = np.array([0.01, 0.03])


class _ZeroMeanGP:
    """GPR with a zero prior mean (Eq. 17 without output normalisation) for residuals: far
    from the data it returns to zero (the green model), and it explains scatter below
    ``noise`` (per output) as noise, not as a wiggly correction. Kernel per output:
    amplitude^2 RBF (length scales at least a fifth of the data's spread) + white noise of at
    least ``noise``^2; hyperparameters by maximum likelihood."""

    def __init__(self, noise) -> None:
        self.noise = np.asarray(noise, float)

    def fit(self, S, Y) -> _ZeroMeanGP:
        from sklearn.gaussian_process import GaussianProcessRegressor
        from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

        S, Y = np.atleast_2d(S), np.atleast_2d(Y)
        spread = np.ptp(S, axis=0)
        self.active_ = np.flatnonzero(spread > 1e-9)
        scale = spread[self.active_]
        self.gps_ = []
        for j in range(Y.shape[1]):
            n2 = float(self.noise[j]) ** 2
            amp = max(float(np.mean(Y[:, j] ** 2)), n2)
            kernel = (ConstantKernel(amp, (1e-3 * n2, 1e2 * amp))
                      * RBF(scale, (0.2 * scale.min(), 100 * scale.max()))
                      + WhiteKernel(n2, (n2, max(1e2 * amp, 2 * n2))))
            gp = GaussianProcessRegressor(kernel=kernel, normalize_y=False,
                                          n_restarts_optimizer=1, random_state=0)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                gp.fit(S[:, self.active_], Y[:, j])
            self.gps_.append(gp)
        return self

    def predict(self, S) -> np.ndarray:
        S = np.atleast_2d(S)[:, self.active_]
        return np.column_stack([gp.predict(S) for gp in self.gps_])


class PassageResidual:
    """What the estimated green still gets wrong: the observed balls' passage of the hole
    (:func:`path_passage` of the camera's paths) less the estimated green's for the same hits,
    learned over the situations by GPR (Eq. 17; a constant from one shot; zero before any).

    A world the green's parameters describe leaves it near zero; one they cannot describe
    (hills of another height, a bump the model lacks) leaves a smooth residual that
    :func:`matching_shots` then aims to cancel.
    """

    def __init__(self) -> None:
        self.S_ = np.zeros((0, 2))
        self.R_ = np.zeros((0, 2))
        self._gp = None

    def fit(self, green: Green, observations: list[Observation], holes) -> PassageResidual:
        """From the observations of balls that did not sink and their holes, on ``green`` (a
        sunk ball's path ends where it dropped, at the hole's edge: its passage is not
        observed)."""
        obs = [(o, h) for o, h in zip(observations, holes) if o is not None and not o.sunk]
        self._gp = None
        if not obs:
            self.S_, self.R_ = np.zeros((0, 2)), np.zeros((0, 2))
            return self
        B = np.array([o.ball for o, _ in obs])
        H = np.array([h for _, h in obs])
        model = hole_passage(green, B, H, np.array([o.alpha for o, _ in obs]),
                             np.array([o.kappa for o, _ in obs]))
        a_roll = 5 / 7 * green.field.rolling_resistance * 9.81
        seen = np.array([path_passage(o.path, o.times, h, a_roll) for o, h in obs])
        self.S_, self.R_ = H - B, seen - model
        if len(np.unique(np.round(self.S_, 9), axis=0)) >= 2:
            self._gp = _ZeroMeanGP(RESIDUAL_NOISE).fit(self.S_, self.R_)
        return self

    def __call__(self, S) -> np.ndarray:
        """The residual (side distance [m], squared speed [m^2/s^2]) at situations S (n, 2)."""
        S = np.atleast_2d(np.asarray(S, float))
        if len(self.R_) == 0:
            return np.zeros((len(S), 2))
        if self._gp is None:
            return np.tile(self.R_.mean(axis=0), (len(S), 1))
        return self._gp.predict(S)


def matching_shots(green: Green, balls, holes, alphas, kappas, iterations: int = 8,
                   tolerance=(0.003, 0.01), residual=None, max_turn: float = 10.0
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The hits on the estimated green whose balls pass their holes as the given hits' balls
    pass them on the nominal green: at the same side distance and the same speed
    (:func:`hole_passage`): (alpha [rad], kappa, converged) per ball; where the iteration did
    not get within ``tolerance`` (metres, m^2/s^2), its best iterate and False.

    The given hits are the taught ones: they sink on the nominal green, so hits that cross
    the hole in the same way sink on the estimated one; on a green equal to the nominal they
    are returned unchanged. Gauss-Newton on (alpha, log kappa), all balls at once, with
    finite differences, Levenberg-Marquardt damping and steps of at most 5 deg and 20 % in
    kappa; kappa stays within the robot's measured launch, below :func:`launch_ceiling`:
    where the arm's swing saturates (its joints' speed limits) a faster gain launches no
    faster and the swing strays from the commanded motion, so the best hit below it is
    returned (not converged; :func:`launch_limited` says why), its angle within ``max_turn``
    degrees of the given one (a trust region: aiming a ball that arrives too slowly on an
    uneven green chases chaotic paths; elsewhere the angle is free, as a green far from its
    model, e.g. a flat guess of the arctan field, needs 30 deg). ``residual``
    (:class:`PassageResidual`, optional): what the green still gets wrong, subtracted from
    the passage aimed at (so that the world's ball passes as the nominal one).
    """
    balls = np.atleast_2d(np.asarray(balls, float))
    holes = np.atleast_2d(np.asarray(holes, float))
    A0 = np.asarray(alphas, float).ravel()
    L0 = np.log(np.asarray(kappas, float).ravel())
    nominal = Green(green.nominal, green.stroke)
    goal = hole_passage(nominal, balls, holes, A0, np.exp(L0))
    if residual is not None:
        goal = goal - residual(holes - balls)
    tol = np.asarray(tolerance, float)
    kap = green.stroke.launch_table.kappas
    # the ceiling, or the taught gain where the teacher already chose one above it
    lo = np.log(kap[0])
    hi = np.maximum(np.log(launch_ceiling(green.stroke)), L0)
    A, L = A0.copy(), np.clip(L0, lo, hi)
    n, ha, hl = len(A), 2e-3, 2e-3
    ok = np.zeros(n, bool)
    best = np.full(n, np.inf)
    bA, bL = A.copy(), L.copy()
    for _ in range(int(iterations)):
        E = hole_passage(green, np.vstack([balls] * 3), np.vstack([holes] * 3),
                         np.concatenate([A, A + ha, A]), np.exp(np.concatenate([L, L, L + hl])))
        F = (E[:n] - goal) / tol   # in tolerances: both components count alike
        # at the arm's ceiling and still short, the speed is out of reach: aim for the side
        # only (trading side distance for a little speed would send the ball wide)
        capped = (L >= hi - 1e-9) & (F[:, 1] < -1)
        size = np.max(np.abs(F), axis=1)
        size[capped] = np.abs(F[capped, 0])
        better = size < best
        best[better], bA[better], bL[better] = size[better], A[better], L[better]
        ok = (best < 1) & ~capped
        if np.all(ok | (capped & (best < 1))):
            break
        J = np.stack([(E[n:2 * n] - E[:n]) / ha, (E[2 * n:] - E[:n]) / hl], axis=2) \
            / tol[None, :, None]
        F[capped, 1] = 0.0
        J[capped, 1, :] = 0.0
        # Levenberg-Marquardt with Marquardt's scaling: (J'J + mu diag(J'J)) step = -J'F, a
        # small fixed mu: a Newton step where J is well conditioned, a finite one where a
        # column nearly vanishes (a launch that hardly grows with the gain)
        JtJ = np.einsum("nij,nik->njk", J, J)
        g = np.einsum("nij,ni->nj", J, F)
        d = np.maximum(np.diagonal(JtJ, axis1=1, axis2=2), 1e-12)
        mu = 1e-3
        M = JtJ + mu * d[:, :, None] * np.eye(2)[None] + 1e-12 * np.eye(2)[None]
        step = -np.linalg.solve(M, g[:, :, None])[:, :, 0]
        move = ~(ok | (capped & (best < 1)))
        A[move] += np.clip(step[move, 0], -np.deg2rad(5.0), np.deg2rad(5.0))
        # the trust region holds where the speed is out of reach (aiming for the side only)
        A = np.where(capped, np.clip(A, A0 - np.deg2rad(max_turn), A0 + np.deg2rad(max_turn)),
                     A)
        L[move] = np.clip(L[move] + np.clip(step[move, 1], -0.2, 0.2), lo, hi[move])
    return bA, np.exp(bL), ok


def launch_ceiling(stroke: Stroke) -> float:
    """The largest speed gain at which the robot's measured launch still grows with the gain:
    above it the arm's swing saturates (its joints' speed limits), a faster gain launches the
    ball no faster and the swing strays from the commanded motion. From the launch table:
    the last gain up to which, at every hitting angle, each step of the table's gains
    raises the launch speed by at least half in proportion."""
    t = stroke.launch_table
    A, K = np.meshgrid(t.alphas, t.kappas)
    club = np.linalg.norm(stroke.with_launch(None).club_velocity(A.ravel(), K.ravel())[:, :2],
                          axis=1).reshape(A.shape)
    speed = t.speed_factor * club
    grows = speed[1:] >= speed[:-1] * (1 + 0.5 * (t.kappas[1:, None] / t.kappas[:-1, None] - 1))
    i = 0
    while i < len(t.kappas) - 1 and grows[i].all():
        i += 1
    return float(t.kappas[max(i, 1)])


def launch_limited(green: Green, balls, holes, alphas, kappas, residual=None) -> np.ndarray:
    """Whether each hit (alpha [rad], kappa) -- a :func:`matching_shots` result that did not
    converge -- is held back by the arm: its ball arrives at the hole slower than the taught
    hit's on the nominal green (or stops short of it) on the estimated green, and its gain is
    at the robot's :func:`launch_ceiling`."""
    balls = np.atleast_2d(np.asarray(balls, float))
    holes = np.atleast_2d(np.asarray(holes, float))
    A = np.asarray(alphas, float).ravel()
    K = np.asarray(kappas, float).ravel()
    nominal = Green(green.nominal, green.stroke)
    goal = hole_passage(nominal, balls, holes, A, K)
    if residual is not None:
        goal = goal - residual(holes - balls)
    short = hole_passage(green, balls, holes, A, K)[:, 1] < goal[:, 1] - 0.01
    return short & (K >= launch_ceiling(green.stroke) * 0.995)


def fastest_launch(green: Green, alpha: float = 0.0) -> float:
    """The robot's launch at hitting angle ``alpha`` [rad] and its :func:`launch_ceiling` on
    the estimated green [m/s]."""
    V = green.launch_stroke.launch_velocity(np.array([float(alpha)]),
                                            np.array([launch_ceiling(green.stroke)]))
    return float(np.linalg.norm(V[0]))


def adapt(scene: Scene, world: World, base, data: HittingDataset, budget: int,
          rng: np.random.Generator | None = None, method: str = "", progress=None,
          n_candidates: int = 256, n_teach: int = 24, snapshots=()) -> Adaptation:
    """Correct a taught hitting-parameter model from at most ``budget`` shots on the world
    (module docstring).

    Parameters
    ----------
    scene : Scene
        The nominal scene (robot, nominal field, motion, the robot's measured launch): what
        the robot knows.
    world : World
        Where the shots are played.
    base : fitted model
        The taught hitting-parameter model (GPR or GMR on ``data``).
    data : HittingDataset
        The teacher's data set ``base`` was fitted on (its strategy, situations and launch).
    budget : int
        Adaptation shots (>= 0).
    rng : numpy Generator, optional
        Draws the candidate situations (default: seed 0).
    method : str
        The learner's name (a label in the shots).
    progress : callable, optional
        Called with a line of text after each shot.
    n_candidates : int
        Situations drawn from the field's declaration to choose the shots from.
    n_teach : int
        Situations of the data set (equally spaced) the correction is learned on.
    snapshots : iterable of int
        Numbers of shots after which the corrected model is kept as well (in
        :attr:`Adaptation.snapshots`; for learning curves).

    Returns
    -------
    Adaptation
    """
    if int(budget) < 0:
        raise ValueError(f"the adaptation budget must be >= 0 shots, got {budget}")
    rng = np.random.default_rng(0) if rng is None else rng
    fixed = float(data.kappa[0]) if data.strategy == "fixed_speed" else None
    model = CorrectedModel(base, fixed)
    out = Adaptation(model, world)
    keep = sorted({int(k) for k in snapshots if 0 <= int(k) < int(budget)})
    if 0 in keep:
        out.snapshots[0] = CorrectedModel(base, fixed)
    if int(budget) == 0:
        return out
    stroke = scene.stroke if scene.launch_table is not None else data.stroke
    green = Green(scene.field, stroke)
    world_scene = Scene(scene.robot, world.field, scene.motion, scene.launch_table,
                        scene.motion_folder)
    cand = scene.field.situations.sample(int(n_candidates), rng)
    spread = np.ptp(cand[1] - cand[0], axis=0)
    scale = np.where(spread > 1e-9, spread, 1.0)
    played, observations, holes_seen = [], [], []
    residual = PassageResidual()
    for k in range(int(budget)):
        i = next_situation(cand, np.array(played).reshape(-1, 2), scale)
        ball, hole = cand[0][i], cand[1][i]
        s = hole - ball
        a_deg, kap = model.taught(s[None])[0]
        if observations:   # the taught shot, corrected for the green estimated so far
            a1, k1, _ = matching_shots(green, ball[None], hole[None], [np.deg2rad(a_deg)],
                                       [kap], residual=residual)
            a_deg, kap = float(np.rad2deg(a1[0])), float(k1[0])
        shot = Shot(ball, hole, float(np.deg2rad(a_deg)), float(kap), method=method, index=k)
        res = play_shot(world_scene, shot, engine=world.engine)
        played.append(s)
        obs = Observation.from_result(res)
        if obs is not None:
            observations.append(obs)
            holes_seen.append(hole)
            green = estimate_green(green, observations)
            residual = PassageResidual().fit(green, observations, holes_seen)
        miss = 0.0 if res.sunk else float(np.linalg.norm(res.final_position - hole))
        out.steps.append(AdaptationStep(res, green.q.copy(), miss))
        if k + 1 in keep:
            out.snapshots[k + 1] = _learn_correction(CorrectedModel(base, fixed), green, data,
                                                     n_teach, residual)
        if progress is not None:
            progress(f"adaptation shot {k + 1}/{budget} ({method}): "
                     + ("sunk" if res.sunk else res.reason) + f"; green: {green.describe()}")
    _learn_correction(model, green, data, n_teach, residual)
    out.green = green
    out.residual = residual
    out.snapshots[int(budget)] = model
    return out


def _learn_correction(model: CorrectedModel, green: Green, data: HittingDataset,
                      n_teach: int, residual: PassageResidual | None = None) -> CorrectedModel:
    """The correction over the situations: the teacher's good shots at ``n_teach`` of the data
    set's situations (equally spaced) moved onto the estimated green (:func:`matching_shots`),
    less the taught model's predictions there, learned by the model's GPR; returns
    ``model`` (``model.limited_``: how many of those situations the arm's launch cannot
    serve, :func:`launch_limited`; their fastest hit is learned where it is aimed as taught)."""
    idx = np.unique(np.linspace(0, len(data) - 1, min(int(n_teach), len(data))).round()
                    .astype(int))
    A1, K1, ok = matching_shots(green, data.ball[idx], data.hole[idx], data.alpha[idx],
                                data.kappa[idx], residual=residual)
    limited = np.zeros(len(idx), bool)
    aimed = np.zeros(len(idx), bool)
    if not ok.all():
        b, h = data.ball[idx][~ok], data.hole[idx][~ok]
        limited[~ok] = launch_limited(green, b, h, A1[~ok], K1[~ok], residual=residual)
        # of those, the ones whose side distance was met: the fastest hit, well aimed
        goal = hole_passage(Green(green.nominal, green.stroke), b, h, data.alpha[idx][~ok],
                            data.kappa[idx][~ok])[:, 0]
        if residual is not None:
            goal = goal - residual(h - b)[:, 0]
        passage = hole_passage(green, b, h, A1[~ok], K1[~ok])
        aimed[~ok] = np.abs(passage[:, 0] - goal) < 0.003
        stops = np.zeros(len(idx), bool)
        # short of the hole's edge, not of its centre (a ball that stops over the hole drops)
        a_roll = 5 / 7 * green.field.rolling_resistance * 9.81
        stops[~ok] = passage[:, 1] < -2 * a_roll * green.nominal.hole_radius
        model.limited_ = (int(limited.sum()), len(idx), int((limited & stops).sum()))
    else:
        model.limited_ = (0, len(idx), 0)
    # against the taught model's own predictions there: the correction also takes out the
    # model's error at these situations (GMR smooths the teacher's shots)
    T = model.taught(data.situations[idx])
    C = np.column_stack([np.rad2deg(A1) - T[:, 0], np.log(K1 / T[:, 1])])
    use = ok | (limited & aimed)
    if use.any():
        model.fit_correction(data.situations[idx][use], C[use])
    return model
