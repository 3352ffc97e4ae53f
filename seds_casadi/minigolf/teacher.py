"""The teacher: good hitting parameters for the situations a field declares, found on the
field's ball model.

The paper (Sections 3, 5 and 7.2) trains the hitting-parameter model on examples of good shots
given by a teacher. Here the teacher searches the ball model of :mod:`seds_casadi.minigolf.ball`:

* A hit is the learned motion's default hit turned by alpha and scaled by kappa (Eq. 14 at the
  ball): club-head velocity kappa v* R_alpha psi*
  (:class:`~seds_casadi.minigolf.stroke.Stroke`), ball launch velocity by
  :func:`seds_casadi.minigolf.ball.impact`.
* The **situation** s is the hole's position relative to the ball in the field's plane (2-D);
  the situations taught are spread over those the field declares
  (:mod:`seds_casadi.minigolf.situations`; 20 along a slider, a grid of 56 over a region).
* A **success map** (Fig. 4a) is success or failure over an (alpha, kappa) grid for one
  situation. Successful regions that are not connected are different **strategies**; training
  data must come from one strategy (Fig. 4b), so the teacher keeps one across the data set: it
  teaches the most central situation by its rule, then each next situation from its nearest
  taught neighbour, taking the successful region nearest to the neighbour's choice.
* Inside the region, the **speed is chosen by the teacher's strategy**
  (:data:`~seds_casadi.minigolf.fields.TEACHER_STRATEGIES`, a field file may name one):

  - ``"fixed_speed"`` (the paper's flat fields and double hill): kappa is fixed for every
    situation (default: the gain whose straight putt would stop :data:`FIXED_SPEED_OVERSHOOT`
    past the hole on flat ground); alpha is the middle of the successful interval nearest to
    the straight line to the hole (or to the neighbour's angle).
  - ``"minimal_speed"`` (the paper's arctan): the region of the slowest successful hit; its
    slowest gain kappa_min at which an angle interval of at least ``min_width`` (1 deg)
    sinks is found to 1e-4 by bisection, and the teacher hits ``speed_margin`` faster,
    kappa = (1 + speed_margin) kappa_min (the slowest hit itself only just reaches the hole,
    and the thin tips of a region come and go with the search grid), with alpha in the
    middle of the region's interval at that speed.
  - ``"centre"`` (the default for a field of your own): the hit most likely to sink when it is
    executed with errors of ``tolerance`` = (sigma_alpha [deg], sigma_kappa): the success
    region blurred by that Gaussian, the weighted centre of its top tenth, alpha then centred
    in the region's interval at that speed.

  In every case alpha is the middle of an interval whose edges are found on a grid ten times
  finer than the search, so the taught angles carry no more than about 0.05 deg of the grid's
  noise; choices that move smoothly with the situation keep the data learnable.
* Situations without a successful hit are an error that names them and what to change
  (:class:`TeachingError`), unless ``missing="drop"``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..motion.golf import G
from .ball import simulate_shots
from .ball_physics import MU_SLIDE
from .fields import TEACHER_STRATEGIES, Field, load_field
from .hitting_data import HittingDataset, paper_situations
from .stroke import Stroke

__all__ = ["Teacher", "TeachingError", "success_map", "collect_dataset", "teacher_ranges",
           "FIXED_SPEED_OVERSHOOT",
           "default_strategy", "components"]

FIXED_SPEED_OVERSHOOT = 0.6  # m past the hole for the fixed-speed strategy's default gain
DEFAULTS = {"strategy": "centre", "alpha_range": (-40.0, 40.0), "kappa_range": (0.8, 2.4),
            "banks": False}


class TeachingError(ValueError):
    """The teacher found no successful shot for some declared situations.

    Attributes
    ----------
    balls, holes : array, shape (m, 2)
        The situations without one.
    """

    def __init__(self, message: str, balls: np.ndarray, holes: np.ndarray) -> None:
        super().__init__(message)
        self.balls, self.holes = balls, holes


def teacher_ranges(field: Field) -> tuple[tuple[float, float], tuple[float, float]]:
    """The teacher's search box for a field: (alpha_range [deg], kappa_range), from the field
    file's ``"teacher"`` entry or :data:`DEFAULTS`."""
    t = field.teacher
    return (tuple(float(v) for v in t.get("alpha_range", DEFAULTS["alpha_range"])),
            tuple(float(v) for v in t.get("kappa_range", DEFAULTS["kappa_range"])))


def default_strategy(field: Field) -> str:
    """The strategy a field's file names (``"teacher": {"strategy": ...}``), else ``"centre"``
    (the shipped files name the paper's: fixed speed, and minimal speed on arctan)."""
    return field.teacher.get("strategy", DEFAULTS["strategy"])


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
    # without banks a shot that touched a wall is no success: its roll ends there
    res = simulate_shots(field, np.tile(np.asarray(ball, float), (len(V), 1)), V, hole=hole,
                         engine=engine, stop_at_walls=not banks)
    ok = res.sunk if banks else res.sunk & (res.wall_contacts == 0)
    return ok.reshape(K.shape)


def true_runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """(start, stop) index pairs of the True runs of a 1-D mask."""
    m = np.concatenate([[False], mask, [False]]).astype(int)
    d = np.diff(m)
    return list(zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1)))


def components(M: np.ndarray) -> np.ndarray:
    """Labels of the connected components of a boolean grid, diagonal neighbours connected
    (0 = background): a thin success region that runs diagonally across the grid stays one
    region, instead of breaking into pieces that look like separate strategies."""
    from scipy import ndimage

    return ndimage.label(np.asarray(M, bool), structure=np.ones((3, 3), int))[0]


def blurred(mask: np.ndarray, sigma_cells: tuple[float, float]) -> np.ndarray:
    """Probability that a hit aimed at each cell lands in ``mask`` when it is executed with
    Gaussian errors of ``sigma_cells`` (rows, columns; in grid cells): the mask blurred."""
    from scipy import ndimage

    return ndimage.gaussian_filter(np.asarray(mask, float), sigma=sigma_cells, mode="constant")


@dataclass
class Teacher:
    """Finds good (alpha, kappa) for situations on a field's ball model (module docstring).

    Data collection, not learning: a configured search on the ball model with nothing fitted;
    :meth:`collect` (or :func:`collect_dataset`) returns the good shots as a
    :class:`~seds_casadi.minigolf.hitting_data.HittingDataset`, which the hitting-parameter
    estimators (:func:`~seds_casadi.minigolf.parameters.make_model`) are fitted on.

    Settings left at None take the field file's ``"teacher"`` entry, else the defaults
    (:data:`DEFAULTS`).

    Parameters
    ----------
    field : Field
    stroke : Stroke
    strategy : {"fixed_speed", "minimal_speed", "centre"} or None
    kappa : float or None
        The fixed speed gain (``"fixed_speed"``); None: a straight putt that would stop
        :data:`FIXED_SPEED_OVERSHOOT` past the hole on flat ground.
    alpha_range : (float, float) or None
        Angles searched [deg] (default -40, 40).
    kappa_range : (float, float) or None
        Speed gains searched (default 0.8, 2.4).
    resolution : (int, int)
        Grid of the search (angles, gains); the choice is refined on a finer grid.
    banks : bool or None
        Whether shots off a wall count as good shots (default False). The paper's teacher
        played direct shots; bank shots are other strategies (a data set that mixes them with
        direct shots cannot be learned, Fig. 4b).
    speed_margin : float
        ``"minimal_speed"``: the teacher hits this fraction faster than the slowest gain that
        sinks over an angle interval of ``min_width``.
    min_width : float
        ``"minimal_speed"``: the angle interval [deg] that must sink at the slowest gain
        (thinner tails of a success region are left out: they come and go with the search
        grid's resolution).
    tolerance : (float, float)
        ``"centre"``: the execution errors (sigma of alpha [deg], sigma of kappa) the centre
        of a success region is measured against.
    """

    field: Field
    stroke: Stroke
    strategy: str | None = None
    kappa: float | None = None
    alpha_range: tuple | None = None
    kappa_range: tuple | None = None
    resolution: tuple = (161, 65)
    engine: str = "auto"
    banks: bool | None = None
    speed_margin: float = 0.03
    min_width: float = 1.0
    tolerance: tuple = (1.0, 0.03)
    _fixed: float = field(init=False, default=0.0, repr=False)

    def __post_init__(self) -> None:
        settings = {**DEFAULTS, **self.field.teacher}
        for key in ("strategy", "alpha_range", "kappa_range", "banks", "kappa"):
            if getattr(self, key) is None:
                setattr(self, key, settings.get(key))
        if self.strategy not in TEACHER_STRATEGIES:
            raise ValueError(f"unknown strategy {self.strategy!r}; valid: "
                             f"{', '.join(TEACHER_STRATEGIES)}")
        lo, hi = self.alpha_range
        if not lo < hi:
            raise ValueError(f"alpha_range must be (low, high) with low < high, got "
                             f"{self.alpha_range}")
        if not 0 < self.kappa_range[0] < self.kappa_range[1]:
            raise ValueError(f"kappa_range must be (low, high), 0 < low < high, got "
                             f"{self.kappa_range}")
        if self.kappa is not None and not (np.isfinite(self.kappa) and self.kappa > 0):
            raise ValueError(f"kappa must be positive, got {self.kappa}")
        n_a, n_k = self.resolution
        if int(n_a) < 3 or int(n_k) < 3:
            raise ValueError(f"resolution must be at least (3, 3), got {self.resolution}")
        if not 0 <= self.speed_margin < 1:
            raise ValueError(f"speed_margin must be in [0, 1), got {self.speed_margin}")
        if not (np.isfinite(self.min_width) and self.min_width > 0):
            raise ValueError(f"min_width must be positive [deg], got {self.min_width}")
        if not (len(self.tolerance) == 2 and min(self.tolerance) > 0):
            raise ValueError(f"tolerance must be two positive numbers (sigma of alpha [deg], "
                             f"sigma of kappa), got {self.tolerance}")
        if self.stroke.launch_table is not None:
            self._check_launch_speed()
        # the fixed gain of "fixed_speed" (the others choose theirs per situation)
        self._fixed = (float(self.kappa) if self.kappa is not None
                       else self._default_kappa() if self.strategy == "fixed_speed"
                       else np.nan)

    def _level_putt_speed(self, dist: float) -> float:
        """The launch speed that rolls a ball ``dist`` metres on level ground of this field:
        v0 skids to 5/7 v0 over d_s = 24/98 v0^2/(mu g) (see ball), then rolls (5/7 v0)^2 /
        (2 a_roll); d_s + d_r = dist solved for v0."""
        a_roll = 5 / 7 * self.field.rolling_resistance * G
        c = 24 / 98 / (MU_SLIDE * G) + (5 / 7) ** 2 / (2 * max(a_roll, 1e-9))
        return float(np.sqrt(max(dist, 0.0) / c))

    def _check_launch_speed(self) -> None:
        """A robot's measured launch: refuse, before any search, an arm that cannot launch the
        ball fast enough for the nearest declared situation, even with the field's whole drop
        helping it (a lower bound on the speed needed: energy, v^2 >= v_level^2 - 10/7 g h)."""
        f, table = self.field, self.stroke.launch_table
        balls, holes = f.situations.design()
        dist = float(np.min(np.linalg.norm(holes - balls, axis=1))) - f.hole_radius
        drop = f.surface.extremes(f.bounds)["height_range"]
        need = float(np.sqrt(max(self._level_putt_speed(dist) ** 2 - 10 / 7 * G * drop, 0.0)))
        lo, hi = self.kappa_range
        A, K = np.meshgrid(np.deg2rad(np.linspace(*self.alpha_range, 41)),
                           np.linspace(lo, hi, 121))
        fastest = float(np.max(np.linalg.norm(
            self.stroke.launch_velocity(A.ravel(), K.ravel()), axis=1)))
        if fastest < need:
            raise ValueError(
                f"the {table.robot or 'robot'} launches the ball at most at {fastest:.2f} m/s "
                f"(kappa {lo:g}..{hi:g}, alpha {self.alpha_range[0]:g}..{self.alpha_range[1]:g}"
                f" deg), and the nearest declared putt on {f.name} ({dist:.2f} m to the hole's "
                f"edge) needs at least {need:.2f} m/s: declare situations nearer the hole, give "
                f"the teacher a wider kappa_range, or use an arm that swings faster")

    def _default_kappa(self) -> float:
        f = self.field
        balls, holes = f.situations.design()
        dist = float(np.mean(np.linalg.norm(holes - balls, axis=1))) + FIXED_SPEED_OVERSHOOT
        v0 = self._level_putt_speed(dist)
        if self.stroke.launch_table is None:   # the ideal club: the launch is linear in kappa
            club = np.linalg.norm(self.stroke.launch_velocity(0.0, 1.0)[0])
            return float(v0 / club)
        # a robot's measured launch: the slowest gain in kappa_range that launches at v0 at
        # every declared situation's straight aim (an arm's launch can weaken as the hit
        # turns: the Panda's at 9 deg needs 6 % more gain than straight)
        lo, hi = self.kappa_range
        ks = np.linspace(lo, hi, 801)
        aims = np.unique(np.round(self.stroke.aim(holes - balls), 4))
        A, K = np.meshgrid(aims, ks)
        each = np.linalg.norm(self.stroke.launch_velocity(A.ravel(), K.ravel()),
                              axis=1).reshape(K.shape)
        speed = each.min(axis=1)
        if speed.max() < v0:
            weak = aims[int(np.argmin(each.max(axis=0)))]
            raise ValueError(
                f"the {self.stroke.launch_table.robot or 'robot'} launches the ball at most at "
                f"{speed.max():.2f} m/s over kappa {lo:g}..{hi:g} at the declared situations' "
                f"aims (at {np.rad2deg(weak):+.1f} deg: {each[:, np.argmin(each.max(axis=0))].max():.2f}"
                f" m/s), and a putt on {f.name} needs {v0:.2f} m/s (to roll {dist:.2f} m): "
                f"give the field's teacher a fixed 'kappa', declare situations nearer the hole "
                f"or straighter to it, or use an arm that swings faster")
        return float(ks[int(np.argmax(speed >= v0))])

    @property
    def fixed_kappa(self) -> float:
        """The fixed speed gain of the ``"fixed_speed"`` strategy."""
        return self._fixed

    def describe(self) -> str:
        """The teacher's settings in words, for messages."""
        speed = (f"kappa {self._fixed:.3f}" if self.strategy == "fixed_speed"
                 else f"kappa {self.kappa_range[0]:g}..{self.kappa_range[1]:g}")
        shots = "bank shots allowed" if self.banks else "direct shots only"
        return (f"strategy {self.strategy}, {speed}, alpha {self.alpha_range[0]:g}.."
                f"{self.alpha_range[1]:g} deg, {shots}")

    # ------------------------------------------------------------------ the search
    def grid(self) -> tuple[np.ndarray, np.ndarray]:
        """The search grid: angles [rad] and speed gains."""
        n_a, n_k = (int(v) for v in self.resolution)
        return (np.deg2rad(np.linspace(*self.alpha_range, n_a)),
                np.linspace(*self.kappa_range, n_k))

    def map(self, ball, hole, alphas=None, kappas=None) -> np.ndarray:
        """The success map of one situation over the search grid (or given angles and gains);
        only direct shots unless ``banks``."""
        if alphas is None or kappas is None:
            ga, gk = self.grid()
            alphas = ga if alphas is None else alphas
            kappas = gk if kappas is None else kappas
        return success_map(self.field, self.stroke, ball, hole, alphas, kappas, self.engine,
                           self.banks)

    def good_shot(self, ball, hole, reference=None) -> tuple[float, float]:
        """(alpha [rad], kappa) that sinks the ball from ``ball`` into ``hole`` by this
        teacher's strategy, or (nan, nan) when the strategy has no successful hit there.

        ``reference`` (alpha [rad], kappa), the choice in a neighbouring situation, keeps the
        strategy: the successful region nearest to it is used (else the rule alone picks)."""
        ball = np.asarray(ball, float)
        hole = np.asarray(hole, float)
        alphas, kappas = self.grid()
        if self.strategy == "fixed_speed":
            goal = float(self.stroke.aim(hole - ball)[0]) if reference is None else reference[0]
            a = self._middle(ball, hole, self._fixed, goal, alphas[0], alphas[-1])
            return (a, self._fixed) if np.isfinite(a) else (np.nan, np.nan)
        M = self.map(ball, hole, alphas, kappas)
        if not M.any():
            return np.nan, np.nan
        lab = components(M)
        comp = lab == self._pick_component(M, lab, alphas, kappas, ball, hole, reference)
        if self.strategy == "minimal_speed":
            kappa, guess = self._minimal(ball, hole, comp, alphas, kappas)
        else:
            kappa, guess = self._centre(comp, alphas, kappas)
        span = 4 * (alphas[1] - alphas[0])
        cols = np.flatnonzero(comp.any(axis=0))
        lo, hi = alphas[cols[0]] - span, alphas[cols[-1]] + span
        # at the minimal speed a bent region can cross the gain's row more than once (its
        # slow tip curls back): the widest crossing is the region's main band
        widest = self.strategy == "minimal_speed"
        a = self._middle(ball, hole, kappa, guess, lo, hi, widest)
        if not np.isfinite(a) and self.strategy == "minimal_speed":
            # the margin left the region (a small one): its slowest wide gain itself
            kappa /= 1 + self.speed_margin
            a = self._middle(ball, hole, kappa, guess, lo, hi, widest)
        return (a, kappa) if np.isfinite(a) else (np.nan, np.nan)

    def _pick_component(self, M, lab, alphas, kappas, ball, hole, reference) -> int:
        """The label of the successful region the shot is taken from."""
        if reference is not None:
            # the region nearest to the neighbour's choice (grid units in both directions)
            ki, ai = np.nonzero(M)
            da = (alphas[ai] - reference[0]) / (alphas[1] - alphas[0])
            dk = (kappas[ki] - reference[1]) / (kappas[1] - kappas[0])
            j = int(np.argmin(da * da + dk * dk))
            return int(lab[ki[j], ai[j]])
        aim = float(self.stroke.aim(hole - ball)[0])
        if self.strategy == "minimal_speed":
            # the slowest successful hits (nearest the straight aim among them)
            first = int(np.nonzero(M.any(axis=1))[0][0])
            cols = np.flatnonzero(M[first])
            return int(lab[first, cols[np.argmin(np.abs(alphas[cols] - aim))]])
        # centre: the region whose best hit is most likely to sink
        P = blurred(M, self._sigma_cells(alphas, kappas))
        best = [P[lab == c].max() for c in range(1, lab.max() + 1)]
        return 1 + int(np.argmax(best))

    def _sigma_cells(self, alphas, kappas) -> tuple[float, float]:
        return (self.tolerance[1] / (kappas[1] - kappas[0]),
                np.deg2rad(self.tolerance[0]) / (alphas[1] - alphas[0]))

    def _minimal(self, ball, hole, comp, alphas, kappas) -> tuple[float, float]:
        """``"minimal_speed"``: (1 + margin) times the slowest gain at which the region's
        widest angle interval is ``min_width`` wide (on the grid, then by bisection between
        two of its rows on a ten times finer angle grid), and the middle of that interval (a
        first guess of the angle)."""
        rows = np.flatnonzero(comp.any(axis=1))
        da = alphas[1] - alphas[0]
        cols = np.flatnonzero(comp.any(axis=0))
        scan = np.arange(alphas[cols[0]] - 3 * da, alphas[cols[-1]] + 3 * da, da / 10)
        need = np.deg2rad(self.min_width)

        memo: dict[float, tuple[float, float]] = {}

        def widest(kappa):
            """The widest successful angle interval at ``kappa`` on the fine scan (its width
            and middle); each gain is simulated once (the steps below ask for some twice)."""
            k = float(kappa)
            if k not in memo:
                runs = true_runs(self.map(ball, hole, scan, [k])[0])
                if not runs:
                    memo[k] = (0.0, np.nan)
                else:
                    a, b = max(runs, key=lambda r: r[1] - r[0])
                    memo[k] = ((b - a) * da / 10, 0.5 * (scan[a] + scan[b - 1]))
            return memo[k]

        grid_width = np.array([max(b - a for a, b in true_runs(comp[r])) for r in rows]) * da
        i = int(rows[np.argmax(grid_width >= need)] if (grid_width >= need).any()
                else rows[np.argmax(grid_width)])
        while i < rows[-1] and widest(kappas[i])[0] < need:
            i += 1
        while i > 0 and widest(kappas[i - 1])[0] >= need:  # the grid missed a wide row
            i -= 1
        hi = kappas[i]
        if i > 0 and widest(hi)[0] >= need:
            lo = kappas[i - 1]
            for _ in range(8):  # to (kappa step) / 256, about 1e-4
                mid = 0.5 * (lo + hi)
                if widest(mid)[0] >= need:
                    hi = mid
                else:
                    lo = mid
        guess = widest(hi)[1]
        if not np.isfinite(guess):
            guess = float(np.mean(alphas[comp[i]]))
        return float(hi * (1 + self.speed_margin)), float(guess)

    def _centre(self, comp, alphas, kappas) -> tuple[float, float]:
        """``"centre"``: the weighted centre of the top tenth of the blurred region (the hits
        most likely to sink under the tolerance errors), as (kappa, alpha guess)."""
        P = blurred(comp, self._sigma_cells(alphas, kappas)) * comp
        top = P >= 0.9 * P.max()
        w = P * top
        K, A = np.meshgrid(kappas, alphas, indexing="ij")
        kappa, guess = float(np.sum(w * K) / w.sum()), float(np.sum(w * A) / w.sum())
        i = int(np.argmin(np.abs(kappas - kappa)))
        if not comp[i].any():  # a bent region whose centre falls outside it
            i, j = np.unravel_index(np.argmax(P), P.shape)
            kappa, guess = float(kappas[i]), float(alphas[j])
        return kappa, guess

    def _middle(self, ball, hole, kappa: float, guess: float, lo: float, hi: float,
                widest: bool = False) -> float:
        """The middle of the successful angle interval at ``kappa`` in [lo, hi] that contains
        ``guess`` (else the nearest one; with ``widest``, the widest one), its edges on a grid
        a tenth of the search's angle step; nan when none sinks."""
        alphas, _ = self.grid()
        step = (alphas[1] - alphas[0]) / 10
        lo, hi = max(lo, alphas[0] - 10 * step), min(hi, alphas[-1] + 10 * step)
        scan = np.arange(lo, hi + 0.5 * step, step)
        row = self.map(ball, hole, scan, [kappa])[0]
        runs = true_runs(row)
        if not runs:
            return np.nan
        mids = np.array([0.5 * (scan[a] + scan[b - 1]) for a, b in runs])
        if widest:
            return float(mids[int(np.argmax([b - a for a, b in runs]))])
        inside = [k for k, (a, b) in enumerate(runs) if scan[a] <= guess <= scan[b - 1]]
        k = inside[0] if inside else int(np.argmin(np.abs(mids - guess)))
        return float(mids[k])

    # ------------------------------------------------------------------ a data set
    def collect(self, balls, holes, progress: bool = False,
                missing: str = "raise") -> HittingDataset:
        """Good shots for many situations, one strategy for the whole set.

        Parameters
        ----------
        balls, holes : array, shape (n, 2)
        progress : bool
            A progress bar on stderr (only on a terminal).
        missing : {"raise", "drop"}
            Situations without a successful hit: a :class:`TeachingError` naming them
            (default), or left out (counted in the data set's ``dropped``).
        """
        from ._progress import progress_bar

        if missing not in ("raise", "drop"):
            raise ValueError(f"missing must be 'raise' or 'drop', got {missing!r}")
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
        spread = np.ptp(S, axis=0)
        span = np.where(spread > 0, spread, 1.0)
        Z = (S - np.median(S, axis=0)) / span
        order = np.argsort(np.sum(Z * Z, axis=1), kind="stable")
        if missing == "raise":
            self._probe_edges(balls, holes, order)
        done: list[int] = []
        for i in progress_bar(order, progress, desc=f"teacher on {self.field.name}",
                              unit="situation", leave=False):
            ref = None
            good = [j for j in done if np.isfinite(out[j, 0])]
            if good:
                j = good[int(np.argmin(np.sum((Z[good] - Z[i]) ** 2, axis=1)))]
                ref = tuple(out[j])
            out[i] = self.good_shot(balls[i], holes[i], ref)
            done.append(i)
        ok = np.isfinite(out[:, 0])
        if not ok.all() and missing == "raise":
            raise self._missing_error(balls[~ok], holes[~ok], len(balls))
        return HittingDataset(self.field.name, self.strategy, balls[ok], holes[ok],
                              out[ok, 0], out[ok, 1], self.stroke, dropped=int((~ok).sum()),
                              declared=self.field.situations.to_spec())

    def _probe_edges(self, balls, holes, order, n: int = 8) -> None:
        """Before the search: the ``n`` situations farthest from the centre (the last of
        ``order``) must each have a successful hit somewhere on the search grid (a whole
        success map without one, or no sinking angle at the fixed gain), else the
        :class:`TeachingError` is raised now, in a second or two, not after the whole set."""
        edge = [int(i) for i in order[::-1][:int(n)]]
        bad = []
        for i in edge:
            if self.strategy == "fixed_speed":
                ok = np.isfinite(self.good_shot(balls[i], holes[i])[0])
            else:
                ok = bool(self.map(balls[i], holes[i]).any())
            if not ok:
                bad.append(i)
        if bad:
            bad.sort()
            raise self._missing_error(balls[bad], holes[bad], len(edge),
                                      probed=len(edge) < len(balls))

    def _missing_error(self, balls, holes, n: int, probed: bool = False) -> TeachingError:
        shown = "; ".join(f"ball {np.round(b, 3).tolist()} hole {np.round(h, 3).tolist()}"
                          for b, h in list(zip(balls, holes))[:8])
        more = f" and {len(balls) - 8} more" if len(balls) > 8 else ""
        which = ("situations at the edge of those declared (probed before the search)"
                 if probed else "situations")
        return TeachingError(
            f"the teacher ({self.describe()}) found no successful shot for {len(balls)} of {n} "
            f"{which} on {self.field.name}: {shown}{more}. Change the field file: widen the "
            f"'teacher' entry's kappa_range or alpha_range, allow bank shots (\"banks\": true), "
            f"choose another strategy, or declare 'situations' that leave these out (a smaller "
            f"ball region or hole slider)", balls, holes)


def collect_dataset(field: Field | str, stroke: Stroke, n: int | None = None,
                    strategy: str | None = None, progress: bool = False,
                    missing: str = "raise", **teacher_kwargs) -> HittingDataset:
    """The teacher's data set for a field: :class:`Teacher` on :func:`paper_situations`
    (``n`` situations spread over those the field declares; the paper's 20 or 56 by
    default)."""
    f = load_field(field) if not isinstance(field, Field) else field
    balls, holes = paper_situations(f, n)
    return Teacher(f, stroke, strategy, **teacher_kwargs).collect(balls, holes, progress,
                                                                  missing)
