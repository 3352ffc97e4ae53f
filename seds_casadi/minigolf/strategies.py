"""Several strategies per field (the paper's proposed extension, Section 8): explore every
successful way to sink the ball in each situation, and cluster them into strategies that are
consistent across situations.

"An interesting approach would be to explore and store several successful parameters for each
situation, and to cluster them into different strategies. When trained with such a data set,
the robot could be programmed to use the strategy most likely to result in a successful attempt
at each hitting point." Here:

1. **Explore.** For each situation, the success map over a wide (alpha, kappa) grid with bank
   shots allowed (:func:`explore_situation`). The successful cells are split by how often the
   ball touched a wall (direct, one bank, more) and into connected regions (diagonal
   neighbours connected); each region of at least ``min_cells`` cells is one successful way
   to play the situation. Its shot is the region's **centre**: the hit most likely to sink
   under execution errors of ``tolerance`` = (sigma_alpha [deg], sigma_kappa) (the region
   blurred by that Gaussian, the weighted centre of its most robust tenth, the angle then
   centred in the region's interval at that gain, as the teacher's ``"centre"`` strategy),
   and that probability is the shot's **robustness**.
2. **Cluster.** Each region's centre shot has a **route**: the walls its ball touches, in
   order (``"direct"``, ``"left"``, ``"far, right"``, ...). Regions are linked across situations
   in the teacher's order (the most central situation first, then each next-nearest one): a
   region joins the strategy of the same route whose shot in the nearest situation already
   explored is closest (distance in units of 10 deg and 0.2 in kappa, at most ``max_jump``),
   one region per strategy and situation (an optimal assignment); a region nothing matches
   starts a new strategy.
3. **Keep.** ``n_strategies="auto"``: the strategies found in at least ``min_coverage`` of
   the situations; an integer N: the N that cover the most situations. Each is a
   :class:`~seds_casadi.minigolf.hitting_data.HittingDataset` of its own (its shots, labelled),
   learned by its own hitting-parameter model (:mod:`seds_casadi.minigolf.strategy_choice`).

Labels are ordered by the strategies' mean hitting speed (0: the slowest).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from ..motion.golf import BALL_RADIUS
from .ball import simulate_shots
from .fields import Field
from .hitting_data import HittingDataset
from .strategy_files import read_strategies, write_strategies
from .stroke import Stroke
from .teacher import blurred, true_runs

_SCALE = np.array([10.0, 0.2])  # the units of the distance between shots (deg, kappa)

__all__ = ["Region", "Strategy", "StrategySet", "explore_situation", "explore",
           "WALL_CLASSES"]

#: how the regions are told apart by wall contacts: 0 (direct), 1 (one bank), 2 (two or more)
WALL_CLASSES = ("direct", "one bank", "banks")


@dataclass
class Region:
    """One successful way to play a situation: a connected region of the success map.

    Attributes
    ----------
    walls : int
        Wall class of its shots (:data:`WALL_CLASSES`).
    alpha : float
        The region's centre shot: angle [rad].
    kappa : float
    robustness : float
        Probability that the centre shot sinks under the exploration's execution errors.
    cells : int
        Size of the region on the exploration grid.
    mask : array of bool, shape (n_kappa, n_alpha) or None
        The region on the grid (kept for figures).
    route : str
        The walls the centre shot's ball touches on its way, in order (``"direct"``, or e.g.
        ``"left"``, ``"far, right"``): :func:`route`.
    """

    walls: int
    alpha: float
    kappa: float
    robustness: float
    cells: int
    mask: np.ndarray | None = field(default=None, repr=False)
    route: str = "direct"


def _outcomes(field: Field, stroke: Stroke, ball, hole, alphas, kappas, engine="auto"):
    """Sunk (bool) and wall class (int) over a grid, shape (n_kappa, n_alpha)."""
    A, K = np.meshgrid(alphas, kappas)
    V = stroke.launch_velocity(A.ravel(), K.ravel())
    r = simulate_shots(field, np.tile(np.asarray(ball, float), (len(V), 1)), V, hole=hole,
                       engine=engine)
    return r.sunk.reshape(K.shape), np.minimum(r.wall_contacts, 2).reshape(K.shape)


def explore_situation(field: Field, stroke: Stroke, ball, hole, alphas, kappas,
                      tolerance=(1.0, 0.03), min_cells: int = 4, engine: str = "auto",
                      keep_masks: bool = False) -> list[Region]:
    """Every successful region of one situation's success map (module docstring, step 1).

    Parameters
    ----------
    alphas : array, shape (n_alpha,)
        Angles [rad], evenly spaced.
    kappas : array, shape (n_kappa,)
        Gains, evenly spaced.
    tolerance : (float, float)
        Execution errors (sigma of alpha [deg], sigma of kappa) of the regions' centres.
    keep_masks : bool
        Keep each region's grid mask (for figures).
    """
    from scipy import ndimage

    ball, hole = np.asarray(ball, float), np.asarray(hole, float)
    alphas, kappas = np.asarray(alphas, float), np.asarray(kappas, float)
    sunk, walls = _outcomes(field, stroke, ball, hole, alphas, kappas, engine)
    da, dk = alphas[1] - alphas[0], kappas[1] - kappas[0]
    sigma = (tolerance[1] / dk, np.deg2rad(tolerance[0]) / da)
    out = []
    for w in range(len(WALL_CLASSES)):
        lab, n = ndimage.label(sunk & (walls == w), structure=np.ones((3, 3), int))
        for c in range(1, n + 1):
            comp = lab == c
            if comp.sum() < min_cells:
                continue
            P = blurred(comp, sigma) * comp
            # the weighted centre of the region's most robust tenth, on a row of the region
            top = P * (P >= 0.9 * P.max())
            kc = float(np.sum(top.sum(axis=1) * kappas) / top.sum())
            i = int(np.argmin(np.abs(kappas - kc)))
            rows = np.flatnonzero(comp.any(axis=1))
            i = int(rows[np.argmin(np.abs(rows - i))])
            guess = float(np.sum(top.sum(axis=0) * alphas) / top.sum())
            alpha = _centre_alpha(field, stroke, ball, hole, float(kappas[i]), guess, w,
                                  alphas[comp[i]].min() - da, alphas[comp[i]].max() + da,
                                  da / 10, engine)
            j = int(np.clip(np.round((alpha - alphas[0]) / da), 0, len(alphas) - 1))
            out.append(Region(w, alpha, float(kappas[i]), float(P[i, j]), int(comp.sum()),
                              comp if keep_masks else None,
                              route(field, stroke, ball, hole, alpha, float(kappas[i]))))
    return out


def route(field: Field, stroke: Stroke, ball, hole, alpha: float, kappa: float) -> str:
    """The walls a shot's ball touches, in order: ``"direct"`` or a comma-separated list of
    ``"near"`` (x min), ``"far"`` (x max), ``"right"`` (y min) and ``"left"`` (y max; left and
    right looking along +x, the way the ball is hit)."""
    r = simulate_shots(field, np.asarray(ball, float)[None],
                       stroke.launch_velocity(alpha, kappa), hole=hole, engine="numpy",
                       record_paths=True)
    b, tol = field.bounds, BALL_RADIUS + 0.01
    names = []
    for p in r.paths[0]:
        for name, near in (("near", p[0] < b[0] + tol), ("far", p[0] > b[1] - tol),
                           ("right", p[1] < b[2] + tol), ("left", p[1] > b[3] - tol)):
            if near and (not names or names[-1] != name):
                names.append(name)
    return ", ".join(names) if names else "direct"


def _centre_alpha(field, stroke, ball, hole, kappa, guess, walls, lo, hi, step, engine):
    """The middle of the interval of angles at ``kappa`` that sink with ``walls`` wall
    contacts and contain ``guess`` (else ``guess``)."""
    scan = np.arange(lo, hi + 0.5 * step, step)
    sunk, w = _outcomes(field, stroke, ball, hole, scan, [kappa], engine)
    runs = true_runs(sunk[0] & (w[0] == walls))
    if not runs:
        return float(guess)
    mids = np.array([0.5 * (scan[a] + scan[b - 1]) for a, b in runs])
    for (a, b), m in zip(runs, mids):
        if scan[a] - step <= guess <= scan[b - 1] + step:
            return float(m)
    return float(mids[np.argmin(np.abs(mids - guess))])


@dataclass
class Strategy:
    """One strategy: consistent successful regions across situations.

    Attributes
    ----------
    label : int
    walls : int
        Wall class of its shots (:data:`WALL_CLASSES`).
    data : HittingDataset
        Its shots (one per situation where it exists), alpha and kappa of each region's centre.
    robustness : array, shape (n_situations,)
        Over all the explored situations: its shot's probability to sink under the execution
        errors (0 where the strategy has no region).
    routes : list of str
        The route of each of its shots (:func:`route`; one route per strategy).
    """

    label: int
    walls: int
    data: HittingDataset
    robustness: np.ndarray
    routes: list = field(default_factory=list)

    @property
    def coverage(self) -> float:
        """Share of the explored situations where the strategy exists."""
        return float(np.mean(self.robustness > 0))

    def describe(self) -> str:
        """In words, for messages and figures."""
        if not self.routes:
            way = WALL_CLASSES[self.walls]
        elif self.routes[0] == "direct":
            way = "direct"
        else:
            walls = self.routes[0].split(", ")
            way = (f"off the {' and '.join(walls)} wall{'s' if len(walls) > 1 else ''}")
        return (f"strategy {self.label}: {way}, kappa {self.data.kappa.mean():.2f} on "
                f"average, in {self.coverage:.0%} of the situations")


@dataclass
class StrategySet:
    """The strategies found on a field (module docstring).

    Attributes
    ----------
    field : str
    ball, hole : array, shape (n, 2)
        The explored situations.
    strategies : list of Strategy
        Ordered by mean speed (label 0 the slowest).
    stroke : Stroke
    settings : dict
        The exploration's settings (grid, tolerance, ...).
    """

    field: str
    ball: np.ndarray
    hole: np.ndarray
    strategies: list[Strategy]
    stroke: Stroke
    settings: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.strategies)

    @property
    def situations(self) -> np.ndarray:
        """s = hole - ball of the explored situations, shape (n, 2)."""
        return self.hole - self.ball

    def dataset(self) -> HittingDataset:
        """All the strategies' shots in one data set, ``labels`` saying whose."""
        ds = [s.data for s in self.strategies]
        return HittingDataset(self.field, "centre", np.concatenate([d.ball for d in ds]),
                              np.concatenate([d.hole for d in ds]),
                              np.concatenate([d.alpha for d in ds]),
                              np.concatenate([d.kappa for d in ds]), self.stroke,
                              labels=np.concatenate([d.labels for d in ds]),
                              declared=ds[0].declared)

    @property
    def robustness(self) -> np.ndarray:
        """Each strategy's robustness at each explored situation, shape (n, n_strategies)."""
        return np.column_stack([s.robustness for s in self.strategies])

    def describe(self) -> str:
        """One line per strategy."""
        return "\n".join(s.describe() for s in self.strategies)

    def label_regions(self, ball, hole, regions: list[Region]) -> list[int | None]:
        """Which strategy each region of a situation belongs to (None: none of the kept
        ones), matched as in the clustering: the same route, the nearest of each strategy's
        shots at the explored situation nearest to this one, within ``max_jump``."""
        from scipy.optimize import linear_sum_assignment

        spread = np.ptp(self.situations, axis=0)
        span = np.where(spread > 0, spread, 1.0)
        s = (np.asarray(hole, float) - np.asarray(ball, float)) / span
        refs = []
        for st in self.strategies:
            d = np.sum((st.data.situations / span - s) ** 2, axis=1)
            j = int(np.argmin(d))
            refs.append((st.data.alpha[j], st.data.kappa[j], st.routes[j]))
        C = np.full((len(regions), len(refs)), 1e6)
        for a, r in enumerate(regions):
            for b, (alpha, kappa, rt) in enumerate(refs):
                if rt == r.route:
                    d = np.hypot(np.rad2deg(r.alpha - alpha) / _SCALE[0],
                                 (r.kappa - kappa) / _SCALE[1])
                    if d <= self.settings.get("max_jump", 2.0):
                        C[a, b] = d
        out: list[int | None] = [None] * len(regions)
        if len(regions) and len(refs):
            for a, b in zip(*linear_sum_assignment(C)):
                if C[a, b] < 1e6:
                    out[a] = self.strategies[b].label
        return out

    def save(self, path: str | os.PathLike) -> None:
        """Write a guarded ``.npz`` file (:mod:`~seds_casadi.minigolf.strategy_files`)."""
        write_strategies(path, self)

    @classmethod
    def load(cls, path: str | os.PathLike) -> StrategySet:
        """Read and re-validate a file written by :meth:`save` (a
        :class:`~seds_casadi.ModelFileError` for anything wrong)."""
        meta, arrays, data = read_strategies(path)
        strategies = [Strategy(k, w, d, arrays["robustness"][:, k], list(r))
                      for k, (w, r, d) in enumerate(zip(meta["walls"], meta["routes"], data))]
        return cls(meta["field"], arrays["ball"], arrays["hole"], strategies, data[0].stroke,
                   meta["settings"])


def _order(S: np.ndarray) -> np.ndarray:
    """The teacher's order: the most central situation first, then by distance from it."""
    spread = np.ptp(S, axis=0)
    Z = (S - np.median(S, axis=0)) / np.where(spread > 0, spread, 1.0)
    return np.argsort(np.sum(Z * Z, axis=1), kind="stable"), Z


def _track(regions: list[list[Region]], S: np.ndarray, max_jump: float) -> list[dict]:
    """Link the regions of all situations into strategies (module docstring, step 2):
    a list of tracks, each ``{situation index: Region}``."""
    from scipy.optimize import linear_sum_assignment

    order, Z = _order(S)
    tracks: list[dict] = []
    visited: list[int] = []
    for i in order:
        cand = []  # (track, its region in the nearest explored situation where it exists)
        for t, tr in enumerate(tracks):
            where = [j for j in visited if j in tr]
            j = where[int(np.argmin([np.sum((Z[j] - Z[i]) ** 2) for j in where]))]
            cand.append((t, tr[j]))
        R = regions[i]
        if cand and R:
            C = np.full((len(R), len(cand)), 1e6)
            for a, r in enumerate(R):
                for b, (_, ref) in enumerate(cand):
                    if ref.route == r.route:
                        d = np.hypot(np.rad2deg(r.alpha - ref.alpha) / _SCALE[0],
                                     (r.kappa - ref.kappa) / _SCALE[1])
                        if d <= max_jump:
                            C[a, b] = d
            rows, cols = linear_sum_assignment(C)
            matched = {a: cand[b][0] for a, b in zip(rows, cols) if C[a, b] < 1e6}
        else:
            matched = {}
        for a, r in enumerate(R):
            if a in matched:
                tracks[matched[a]][i] = r
            else:
                tracks.append({i: r})
        visited.append(i)
    return tracks


def explore(field: Field, stroke: Stroke, balls, holes, n_strategies="auto",
            min_coverage: float = 0.5, alpha_range=(-75.0, 75.0), kappa_range=None,
            resolution=(301, 73), tolerance=(1.0, 0.03), min_cells: int = 4,
            max_jump: float = 2.0, engine: str = "auto", progress: bool = False) -> StrategySet:
    """Explore the situations, cluster the successful regions into strategies and keep the
    main ones (module docstring).

    A search, not a learner: nothing is fitted; the :class:`StrategySet` it returns is the data
    that :class:`~seds_casadi.minigolf.strategy_choice.StrategyChoice` is fitted on.

    Parameters
    ----------
    field : Field
    stroke : Stroke
    balls, holes : array, shape (n, 2)
        The situations (e.g. the teacher's, :func:`~seds_casadi.minigolf.teacher.
        paper_situations`).
    n_strategies : "auto" or int
        "auto": the strategies present in at least ``min_coverage`` of the situations; N: the
        N most widespread.
    alpha_range : (float, float)
        Angles explored [deg].
    kappa_range : (float, float) or None
        Gains explored (default: the field's teacher's range, else 0.6..2.4).
    resolution : (int, int)
        Exploration grid (angles, gains).
    tolerance : (float, float)
        Execution errors (sigma of alpha [deg], sigma of kappa) of the regions' centres.
    min_cells : int
        Smaller regions are left out (specks of the grid).
    max_jump : float
        Largest change of a strategy's shot between neighbouring situations, in units of 10
        deg and 0.2 in kappa.
    progress : bool
        A progress bar (on a terminal).

    Returns
    -------
    StrategySet
    """
    from ._progress import progress_bar

    if not (n_strategies == "auto" or (isinstance(n_strategies, (int, np.integer))
                                       and not isinstance(n_strategies, bool)
                                       and n_strategies >= 1)):
        raise ValueError(f"n_strategies must be 'auto' or an integer >= 1, got "
                         f"{n_strategies!r}")
    if not 0 < min_coverage <= 1:
        raise ValueError(f"min_coverage must be in (0, 1], got {min_coverage}")
    balls = np.atleast_2d(np.asarray(balls, float))
    holes = np.atleast_2d(np.asarray(holes, float))
    field.check_situation(balls)
    if kappa_range is None:
        kappa_range = field.teacher.get("kappa_range", (0.6, 2.4))
    alphas = np.deg2rad(np.linspace(*alpha_range, int(resolution[0])))
    kappas = np.linspace(*kappa_range, int(resolution[1]))
    regions = [explore_situation(field, stroke, b, h, alphas, kappas, tolerance, min_cells,
                                 engine)
               for b, h in progress_bar(list(zip(balls, holes)), progress,
                                        desc=f"exploring strategies on {field.name}",
                                        unit="situation", leave=False)]
    tracks = _track(regions, holes - balls, max_jump)
    n = len(balls)
    cover = np.array([len(t) / n for t in tracks])
    if n_strategies == "auto":
        keep = [t for t, c in enumerate(cover) if c >= min_coverage]
    else:
        keep = list(np.argsort(-cover, kind="stable")[:int(n_strategies)])
    if not keep:
        raise ValueError(f"no strategy sinks the ball in {min_coverage:.0%} of the "
                         f"{n} situations on {field.name} (the most widespread in "
                         f"{cover.max() if len(cover) else 0:.0%}); lower min_coverage, give "
                         f"a number of strategies, or widen the ranges explored")
    speed = [np.mean([r.kappa for r in tracks[t].values()]) for t in keep]
    keep = [keep[k] for k in np.argsort(speed, kind="stable")]
    strategies = []
    for label, t in enumerate(keep):
        idx = np.array(sorted(tracks[t]))
        rs = [tracks[t][i] for i in idx]
        rob = np.zeros(n)
        rob[idx] = [r.robustness for r in rs]
        data = HittingDataset(field.name, "centre", balls[idx], holes[idx],
                              np.array([r.alpha for r in rs]), np.array([r.kappa for r in rs]),
                              stroke, labels=np.full(len(idx), label),
                              declared=field.situations.to_spec())
        strategies.append(Strategy(label, rs[0].walls, data, rob, [r.route for r in rs]))
    settings = {"alpha_range": list(alpha_range), "kappa_range": list(kappa_range),
                "resolution": [int(v) for v in resolution], "tolerance": list(tolerance),
                "min_cells": int(min_cells), "max_jump": float(max_jump),
                "n_strategies": n_strategies if n_strategies == "auto" else int(n_strategies),
                "min_coverage": float(min_coverage), "found": len(tracks)}
    return StrategySet(field.name, balls, holes, strategies, stroke, settings)
