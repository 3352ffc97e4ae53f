"""The teacher: good hitting parameters for a situation, found on the field's ball model.

The paper (Sections 3, 5 and 7.2) trains the hitting-parameter model on examples of good shots
given by a teacher. Here the teacher searches the ball model of :mod:`seds_casadi.minigolf.ball`:

* A hit is the learned motion's default hit turned by alpha and scaled by kappa (Eq. 14 at the
  ball): club-head velocity kappa v* R_alpha psi*
  (:class:`~seds_casadi.minigolf.stroke.Stroke`), ball launch velocity by
  :func:`seds_casadi.minigolf.ball.impact`.
* The **situation** s is the hole's position relative to the ball in the field's plane (2-D).
* A **success map** (Fig. 4a) is success or failure over an (alpha, kappa) grid for one
  situation. Successful regions that are not connected are different **strategies**; training
  data must come from one strategy (Fig. 4b), so the teacher keeps one, as the paper did:

  - ``"fixed_speed"`` (flat fields and the double hill): kappa is fixed for every situation
    (default: the gain whose straight putt would stop :data:`FIXED_SPEED_OVERSHOOT` past the
    hole on flat ground with the field's rolling resistance); alpha is the middle of the
    successful interval nearest to the straight line to the hole.
  - ``"minimal_speed"`` (arctan): the successful region that contains the slowest successful
    hit; the paper's choice was the slowest hit itself, which sits on the edge of failure (the
    ball just reaches the hole), so this teacher takes kappa a quarter of the way up that
    region's speed range, and alpha in the middle of its interval at that speed (a choice the
    paper leaves open; it makes the examples robust to the ball model's step).

Data sets as in the paper (:func:`~seds_casadi.minigolf.hitting_data.paper_situations`,
kept in a :class:`~seds_casadi.minigolf.hitting_data.HittingDataset`): 20 situations along one
input dimension (the hole moved sideways along the far edge, ball fixed) for the rough flat and
double hill fields, 56 (a 7 x 8 grid of ball positions) for arctan.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .ball import MU_SLIDE, G, simulate_shots
from .fields import Field, load_field
from .hitting_data import HittingDataset, paper_situations, region_centre
from .stroke import Stroke

__all__ = ["Stroke", "Teacher", "HittingDataset", "success_map", "paper_situations",
           "collect_dataset", "STRATEGIES", "FIXED_SPEED_OVERSHOOT", "default_strategy"]

STRATEGIES = ("fixed_speed", "minimal_speed")
FIXED_SPEED_OVERSHOOT = 0.6  # m past the hole for the fixed-speed strategy's default gain


def default_strategy(field: Field) -> str:
    """The paper's strategy for a field: minimal speed on arctan, fixed speed elsewhere."""
    return "minimal_speed" if field.surface.shape == "arctan" else "fixed_speed"


def success_map(field: Field, stroke: Stroke, ball, hole, alphas, kappas,
                engine: str = "auto", banks: bool = True) -> np.ndarray:
    """Fig. 4a: whether each (alpha, kappa) of a grid sinks the ball.

    Parameters
    ----------
    field : Field
    stroke : Stroke
    ball, hole : array, shape (2,)
    alphas : array, shape (n_alpha,)
        Hitting angles [rad].
    kappas : array, shape (n_kappa,)
        Speed gains.
    banks : bool, default True
        Count shots that touch a wall before they sink (False: only direct shots succeed).

    Returns
    -------
    array of bool, shape (n_kappa, n_alpha)
    """
    alphas = np.asarray(alphas, dtype=float).ravel()
    kappas = np.asarray(kappas, dtype=float).ravel()
    A, K = np.meshgrid(alphas, kappas)
    V = stroke.launch_velocity(A.ravel(), K.ravel())
    res = simulate_shots(field, np.tile(np.asarray(ball, float), (len(V), 1)), V, hole=hole,
                         engine=engine)
    ok = res.sunk if banks else res.sunk & (res.wall_contacts == 0)
    return ok.reshape(K.shape)


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """(start, stop) index pairs of the True runs of a 1-D mask."""
    m = np.concatenate([[False], mask, [False]]).astype(int)
    d = np.diff(m)
    return list(zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1)))


def _components(M: np.ndarray) -> np.ndarray:
    """Labels of the 4-connected components of a boolean grid (0 = background)."""
    lab = np.zeros(M.shape, int)
    n = 0
    for i0, j0 in zip(*np.nonzero(M)):
        if lab[i0, j0]:
            continue
        n += 1
        stack = [(i0, j0)]
        lab[i0, j0] = n
        while stack:
            i, j = stack.pop()
            for a, b in ((i + 1, j), (i - 1, j), (i, j + 1), (i, j - 1)):
                if 0 <= a < M.shape[0] and 0 <= b < M.shape[1] and M[a, b] and not lab[a, b]:
                    lab[a, b] = n
                    stack.append((a, b))
    return lab


@dataclass
class Teacher:
    """Finds good (alpha, kappa) for situations on a field's ball model (module docstring).

    Parameters
    ----------
    field : Field
    stroke : Stroke
    strategy : {"fixed_speed", "minimal_speed"} or None
        None: the paper's choice for the field (:func:`default_strategy`).
    kappa : float or None
        The fixed speed gain (``"fixed_speed"``); None: a straight putt that would stop
        :data:`FIXED_SPEED_OVERSHOOT` past the field's hole on flat ground.
    alpha_range : (float, float)
        Angles searched [deg].
    kappa_range : (float, float)
        Speed gains searched (``"minimal_speed"``).
    resolution : (int, int)
        Grid of the search (angles, gains); the angle is refined around the choice.
    banks : bool, default False
        Whether shots off a wall count as good shots. The paper's teacher played direct shots;
        bank shots are a different strategy (on the arctan field the slowest hits are often
        banks, and a data set that mixes them with direct shots cannot be learned, Fig. 4b).
    """

    field: Field
    stroke: Stroke
    strategy: str | None = None
    kappa: float | None = None
    alpha_range: tuple = (-40.0, 40.0)
    kappa_range: tuple = (0.8, 2.4)
    resolution: tuple = (161, 65)
    engine: str = "auto"
    banks: bool = False
    _fixed: float = field(init=False, default=0.0, repr=False)

    def __post_init__(self) -> None:
        if self.strategy is None:
            self.strategy = default_strategy(self.field)
        if self.strategy not in STRATEGIES:
            raise ValueError(f"unknown strategy {self.strategy!r}; valid: {', '.join(STRATEGIES)}")
        lo, hi = self.alpha_range
        if not lo < hi:
            raise ValueError(f"alpha_range must be (low, high) with low < high, got "
                             f"{self.alpha_range}")
        if not 0 < self.kappa_range[0] < self.kappa_range[1]:
            raise ValueError(f"kappa_range must be (low, high), 0 < low < high, got "
                             f"{self.kappa_range}")
        if self.kappa is not None and not (np.isfinite(self.kappa) and self.kappa > 0):
            raise ValueError(f"kappa must be positive, got {self.kappa}")
        self._fixed = float(self.kappa) if self.kappa is not None else self._default_kappa()

    def _default_kappa(self) -> float:
        f = self.field
        dist = np.linalg.norm(f.hole - region_centre(f.ball_region)) + FIXED_SPEED_OVERSHOOT
        a_roll = 5 / 7 * f.rolling_resistance * G
        # launch v0 skids to 5/7 v0 over d_s = 24/98 v0^2/(mu g) (see ball), then rolls
        # (5/7 v0)^2 / (2 a_roll): solve d_s + d_r = dist for v0
        c = 24 / 98 / (MU_SLIDE * G) + (5 / 7) ** 2 / (2 * max(a_roll, 1e-9))
        v0 = np.sqrt(dist / c)
        club = np.linalg.norm(self.stroke.launch_velocity(0.0, 1.0)[0])
        return float(v0 / club)

    @property
    def fixed_kappa(self) -> float:
        """The fixed speed gain of the ``"fixed_speed"`` strategy."""
        return self._fixed

    def good_shot(self, ball, hole, reference=None) -> tuple[float, float]:
        """(alpha [rad], kappa) that sinks the ball from ``ball`` into ``hole`` by this
        teacher's strategy, or (nan, nan) when the strategy has no successful hit there.

        ``reference`` (alpha, kappa), the choice in a neighbouring situation, keeps the
        strategy: the successful region nearest to it is used (else the rule alone picks)."""
        ball = np.asarray(ball, float)
        hole = np.asarray(hole, float)
        n_a, n_k = self.resolution
        alphas = np.deg2rad(np.linspace(*self.alpha_range, n_a))
        aim = float(self.stroke.aim(hole - ball)[0])
        if self.strategy == "fixed_speed":
            row = success_map(self.field, self.stroke, ball, hole, alphas, [self._fixed],
                              self.engine, self.banks)[0]
            runs = _runs(row)
            if not runs:
                return np.nan, np.nan
            mids = [0.5 * (alphas[a] + alphas[b - 1]) for a, b in runs]
            goal = aim if reference is None else reference[0]
            a0, b0 = runs[int(np.argmin([abs(m - goal) for m in mids]))]
            return self._refine(ball, hole, alphas, a0, b0, self._fixed), self._fixed
        kappas = np.linspace(*self.kappa_range, n_k)
        M = success_map(self.field, self.stroke, ball, hole, alphas, kappas, self.engine,
                        self.banks)
        if not M.any():
            return np.nan, np.nan
        lab = _components(M)
        if reference is None:
            first = int(np.nonzero(M.any(axis=1))[0][0])
            # the slowest successful hits (nearest the straight aim among them) pick the region
            cols = np.flatnonzero(M[first])
            comp = lab[first, cols[np.argmin(np.abs(alphas[cols] - aim))]]
        else:
            # the region nearest to the neighbour's choice (grid units in both directions)
            ki, ai = np.nonzero(M)
            da = (alphas[ai] - reference[0]) / (alphas[1] - alphas[0])
            dk = (kappas[ki] - reference[1]) / (kappas[1] - kappas[0])
            j = int(np.argmin(da * da + dk * dk))
            comp = lab[ki[j], ai[j]]
        rows = np.flatnonzero((lab == comp).any(axis=1))
        i = rows[0] + int(round(0.25 * (rows[-1] - rows[0])))
        if reference is not None:
            # continue the neighbour's speed inside the region (not on its slow edge)
            lo_row = min(rows[0] + 1, rows[-1])
            i = int(np.clip(np.argmin(np.abs(kappas - reference[1])), lo_row, rows[-1]))
            if not (lab[i] == comp).any():
                i = rows[np.argmin(np.abs(rows - i))]
        kappa = float(kappas[i])
        runs = _runs(lab[i] == comp)
        a0, b0 = max(runs, key=lambda r: r[1] - r[0])
        return self._refine(ball, hole, alphas, a0, b0, kappa), kappa

    def _refine(self, ball, hole, alphas, a0, b0, kappa) -> float:
        """Middle of a successful angle interval, its edges found on a 10x finer grid."""
        step = alphas[1] - alphas[0]
        lo = np.linspace(alphas[a0] - step, alphas[a0], 11)
        hi = np.linspace(alphas[b0 - 1], alphas[b0 - 1] + step, 11)
        ok = success_map(self.field, self.stroke, ball, hole, np.concatenate([lo, hi]), [kappa],
                         self.engine, self.banks)[0]
        left = lo[np.argmax(ok[:11])] if ok[:11].any() else alphas[a0]
        right = hi[10 - np.argmax(ok[11:][::-1])] if ok[11:].any() else alphas[b0 - 1]
        return float(0.5 * (left + right))

    def collect(self, balls, holes, progress: bool = False) -> HittingDataset:
        """Good shots for many situations; situations without one are dropped (reported in
        the data set's ``dropped``)."""
        balls = np.atleast_2d(np.asarray(balls, float))
        holes = np.atleast_2d(np.asarray(holes, float))
        if balls.shape != holes.shape or balls.shape[1] != 2:
            raise ValueError(f"balls and holes must both have shape (n, 2), got {balls.shape} "
                             f"and {holes.shape}")
        self.field.check_situation(balls)
        out = np.full((len(balls), 2), np.nan)
        # one strategy for the whole set: start from the most central situation by the rule,
        # then teach each next-nearest situation with its nearest taught neighbour's choice as
        # the reference (the paper's teacher kept one strategy by hand)
        S = holes - balls
        span = np.where(np.ptp(S, axis=0) > 0, np.ptp(S, axis=0), 1.0)
        Z = (S - np.median(S, axis=0)) / span
        order = np.argsort(np.sum(Z * Z, axis=1), kind="stable")
        it = order
        if progress:
            from tqdm.auto import tqdm

            it = tqdm(order, desc=f"teacher on {self.field.name}", leave=False)
        done: list[int] = []
        for i in it:
            ref = None
            good = [j for j in done if np.isfinite(out[j, 0])]
            if good:
                j = good[int(np.argmin(np.sum((Z[good] - Z[i]) ** 2, axis=1)))]
                ref = tuple(out[j])
            out[i] = self.good_shot(balls[i], holes[i], ref)
            done.append(i)
        ok = np.isfinite(out[:, 0])
        return HittingDataset(self.field.name, self.strategy, balls[ok], holes[ok],
                              out[ok, 0], out[ok, 1], self.stroke,
                              dropped=int((~ok).sum()))


def collect_dataset(field: Field | str, stroke: Stroke, layout: str | None = None,
                    n: int | None = None, strategy: str | None = None,
                    progress: bool = False, **teacher_kwargs) -> HittingDataset:
    """The paper's data set for a field (:func:`paper_situations`) taught by :class:`Teacher`."""
    f = load_field(field) if not isinstance(field, Field) else field
    balls, holes = paper_situations(f, layout, n)
    return Teacher(f, stroke, strategy, **teacher_kwargs).collect(balls, holes, progress)

