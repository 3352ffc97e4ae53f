"""Replays of shots: the robot's swing and the ball rolling on the field, to watch.

A shot is played again by :func:`seds_casadi.game.shot.play_shot` (the same scene and shot
give the same swing: the 500 Hz controller on Pinocchio's forward dynamics, then the ball
model) and
kept as a :class:`Replay`: per frame, the arm's chain (base, each joint's origin, the flange, the
club head, from Pinocchio's forward kinematics at the simulated configurations), the club
head's face and the ball on the field's surface. :func:`write_replay` writes

* ``replay.html``: a self-contained page (no network, no library: the data are embedded and
  drawn on a canvas in a perspective 3-D view; drag turns it, the wheel zooms, a menu picks
  the shot, a slider scrubs the time);
* ``replay_<learner>_<shot>.gif`` per shot: the same scene in matplotlib's 3-D axes, for papers.

``seds-casadi play --replay [N]`` replays the first N shots of its round.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass

import numpy as np

from ..core._io import atomic_text, data_folder, umask
from ..core._signals import raise_pending_interrupt
from ..game.scene import Scene
from ..game.shot import Shot, play_shot
from ..motion.golf import BALL_RADIUS
from .shot_table import shot_row

__all__ = ["Replay", "replay_shot", "write_replay", "write_replay_html", "write_replay_gif",
           "REPLAY_COLOURS"]

#: colours (RGB 0-255) of the page and the GIF: the screenshot test looks for them
REPLAY_COLOURS = {"field": (70, 150, 70), "robot": (230, 90, 20), "joint": (60, 60, 60),
                  "base": (90, 90, 110), "club": (40, 40, 40), "ball": (255, 255, 255),
                  "hole": (20, 20, 20), "trail": (30, 60, 200), "wall": (120, 80, 40)}


@dataclass(frozen=True)
class Replay:
    """One shot, frame by frame (field frame, z up, metres, seconds).

    Attributes
    ----------
    t : array, shape (n,)
        Frame times from the start of the swing [s], equally spaced by ``frame_dt``.
    chain : array, shape (n, m, 3)
        The arm's points: the base on the floor, each joint's origin, the flange
        (index ``flange_index``) and the club head's centre (the last).
    head_ends : array, shape (n, 2, 3)
        The ends of the club head's face (4 cm across the face's normal).
    ball : array, shape (n, 3)
        The ball's centre (on the surface; below it once sunk).
    hit_time : float
        When the club met the ball (nan: it did not).
    label : str
        The shot's name (learner, number, result).
    row : dict
        The shot's row of ``shots.csv`` (:data:`seds_casadi.app.shot_table.SHOT_COLUMNS`).
    field, robot : str
        Their names.
    """

    t: np.ndarray
    chain: np.ndarray
    head_ends: np.ndarray
    ball: np.ndarray
    flange_index: int
    hit_time: float
    label: str
    row: dict
    field: str
    robot: str

    @property
    def frame_dt(self) -> float:
        return float(self.t[1] - self.t[0]) if len(self.t) > 1 else 1.0


def _chain(robot, q) -> tuple[np.ndarray, np.ndarray]:
    """The arm's points at ``q`` (base, joint origins, flange, head) and the head's face ends."""
    import pinocchio as pin

    pin.forwardKinematics(robot.model, robot.data, np.asarray(q, float))
    M = robot.base_placement
    pts = [np.array(robot.base[:3], float)]
    pts += [M.act(robot.data.oMi[j].translation) for j in range(1, robot.model.njoints)]
    head, R = robot.head_pose(q)
    pts += [head + R[:, 2] * robot.club.length, head]   # the shaft runs along the head's z
    across = R[:, 1] * 0.02
    return np.array(pts), np.array([head - across, head + across])


def replay_shot(scene: Scene, shot: Shot, fps: float = 25.0, max_time: float = 8.0) -> Replay:
    """Play one shot again and keep it frame by frame.

    Parameters
    ----------
    scene : Scene
        The robot, field and motion (:class:`~seds_casadi.game.scene.Scene`).
    shot : Shot
    fps : float
        Frames per second of simulated time.
    max_time : float
        The replay ends at most this long after the swing starts [s] (a long roll is cut).

    Returns
    -------
    Replay
    """
    if not (np.isfinite(fps) and fps > 0 and np.isfinite(max_time) and max_time > 0):
        raise ValueError(f"fps and max_time must be positive, got {fps!r} and {max_time!r}")
    res = play_shot(scene, shot, keep_swing=True)
    swing = res.swing
    if swing is None:
        raise ValueError(f"shot {shot.index} of {shot.method}: {res.reason}; nothing to replay")
    fld = scene.field
    ball0 = shot.ball
    robot = scene.robot_at(ball0)
    row = shot_row(res)
    path = np.asarray(row.pop("path", ball0[None]), float)
    hit_t = swing.hit_time if swing.hit else np.inf
    roll_end = hit_t + 0.01 * (len(path) - 1) + 0.3 if swing.hit else swing.t[-1]
    end = min(max_time, max(float(swing.t[-1]), roll_end))
    t = np.arange(0.0, end + 1e-9, 1.0 / fps)
    k_swing = np.clip(np.searchsorted(swing.t, t), 0, len(swing.t) - 1)
    chains, heads = zip(*(_chain(robot, swing.q[k]) for k in k_swing))
    k_ball = np.clip(np.round((t - hit_t) / 0.01), 0, len(path) - 1)
    k_ball = np.where(t < hit_t, 0, k_ball).astype(int)
    xy = path[k_ball]
    z = fld.surface.height(xy) + BALL_RADIUS
    if row["sunk"]:   # in the hole once it has stopped there
        z = np.where(k_ball == len(path) - 1, z - 2 * BALL_RADIUS, z)
    outcome = "sunk" if row["sunk"] else ("missed" if row["hit"] else "no hit")
    return Replay(t, np.array(chains), np.array(heads), np.column_stack([xy, z]),
                  len(chains[0]) - 2, float(swing.hit_time), f"{shot.method} shot "
                  f"{shot.index} ({outcome})", row, fld.name, str(scene.robot))


def _field_grid(field, n: int = 36) -> dict:
    b = np.asarray(field.bounds, float)
    nx = max(8, int(round(n * (b[1] - b[0]) / max(b[1] - b[0], b[3] - b[2]))))
    ny = max(8, int(round(n * (b[3] - b[2]) / max(b[1] - b[0], b[3] - b[2]))))
    x, y = np.linspace(b[0], b[1], nx), np.linspace(b[2], b[3], ny)
    X, Y = np.meshgrid(x, y)
    Z = field.surface.height(np.column_stack([X.ravel(), Y.ravel()])).reshape(X.shape)
    return {"x": x, "y": y, "z": Z, "bounds": b}


def _r4(a) -> list:
    """Coordinates rounded to 0.1 mm, as JSON lists."""
    return np.round(np.asarray(a, float), 4).tolist()


def _page_data(replays: list[Replay], field, title: str) -> dict:
    g = _field_grid(field)
    shots = [{"label": r.label, "t": _r4(r.t), "frame_dt": r.frame_dt, "chain": _r4(r.chain),
              "head_ends": _r4(r.head_ends), "ball": _r4(r.ball), "flange_index": r.flange_index,
              "hole": _r4([r.row["hole_x_m"], r.row["hole_y_m"]]),
              "alpha_deg": float(r.row["alpha_deg"]), "kappa": float(r.row["kappa"]),
              "sunk": bool(r.row["sunk"])} for r in replays]
    return {"title": title, "shots": shots, "robot": replays[0].robot, "ball_radius": BALL_RADIUS,
            "colours": {k: list(v) for k, v in REPLAY_COLOURS.items()},
            "field": {"x": _r4(g["x"]), "y": _r4(g["y"]), "z": _r4(g["z"]),
                      "zmin": float(g["z"].min()), "zmax": float(g["z"].max()),
                      "bounds": _r4(g["bounds"]), "walls": field.boundary == "walls",
                      "hole_radius": float(field.hole_radius)}}


def _title(replays: list[Replay]) -> str:
    r = replays[0]
    learners = sorted({x.row["method"] for x in replays})
    return (f"seds_casadi replay: the {r.robot} on {r.field}, "
            f"{len(replays)} shot{'s' * (len(replays) > 1)} by {', '.join(learners)}")


def write_replay_html(replays: list[Replay], field, path: str | os.PathLike) -> str:
    """Write the self-contained replay page of ``replays`` (module docstring) to ``path``."""
    if not replays:
        raise ValueError("no shots to replay")
    with open(os.path.join(data_folder("seds_casadi.data"), "replay.html"),
              encoding="utf-8") as fh:
        page = fh.read()
    title = _title(replays)
    data = json.dumps(_page_data(replays, field, title), separators=(",", ":"))
    page = page.replace("__TITLE__", title).replace("__DATA__", data.replace("</", "<\\/"))
    atomic_text(path, page)
    return os.fspath(path)


def write_replay_gif(replay: Replay, field, path: str | os.PathLike, max_frames: int = 60,
                     fps: float = 12.0, dpi: int = 125) -> str:
    """Write one shot as an animated GIF (matplotlib 3-D axes, Pillow) to ``path``.

    8 x 6 inches at ``dpi`` (1000 x 750 pixels by default, for a paper or a slide). The frames
    are spread evenly over the replay (at most ``max_frames``), so a long roll plays faster than
    real time; the title gives the simulated time of each frame."""
    from matplotlib.animation import PillowWriter
    from matplotlib.lines import Line2D

    from .plotting import pyplot

    plt = pyplot()
    c = {k: np.array(v) / 255 for k, v in REPLAY_COLOURS.items()}
    g = _field_grid(field, 24)
    X, Y = np.meshgrid(g["x"], g["y"])
    fig = plt.figure(figsize=(8.0, 6.0))
    ax = fig.add_subplot(projection="3d")
    ax.plot_surface(X, Y, g["z"], color=c["field"], alpha=0.55, linewidth=0, shade=True)
    hole = np.array([replay.row["hole_x_m"], replay.row["hole_y_m"]])
    a = np.linspace(0, 2 * np.pi, 30)
    hx, hy = hole[0] + field.hole_radius * np.cos(a), hole[1] + field.hole_radius * np.sin(a)
    ax.plot(hx, hy, field.surface.height(np.column_stack([hx, hy])) + 1e-3, color="k", lw=1.5)
    pts = np.concatenate([replay.chain.reshape(-1, 3), replay.ball])
    lo = np.minimum(pts.min(0), [g["bounds"][0], g["bounds"][2], 0])
    hi = np.maximum(pts.max(0), [g["bounds"][1], g["bounds"][3], 0.1])
    ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), zlim=(lo[2], hi[2]))
    # the labels clear of the tick labels (3-D axes put them on top of each other by default)
    ax.set_xlabel("x [m]", labelpad=14)
    ax.set_ylabel("y [m]", labelpad=10)
    ax.set_zlabel("z [m]", labelpad=8)
    ax.tick_params(labelsize=8)
    ax.set_box_aspect(hi - lo, zoom=1.05)
    fig.subplots_adjust(left=0.0, right=0.94, bottom=0.02, top=0.92)
    ax.view_init(elev=28, azim=-60)
    arm, = ax.plot([], [], [], "-o", color=c["robot"], lw=4, ms=3, mfc=c["joint"],
                   label=f"{replay.robot} arm")
    club, = ax.plot([], [], [], "-", color=c["club"], lw=2, label="club")
    trail, = ax.plot([], [], [], "-", color=c["trail"], lw=1.5, label="ball path")
    ball, = ax.plot([], [], [], "o", color="w", mec="k", ms=6, label="ball")
    hole_key = Line2D([], [], ls="none", marker="o", ms=9, mfc="none", mec="k", mew=1.5,
                      label="hole")   # a ring, as drawn (not a line)
    ax.legend(handles=[arm, club, trail, ball, hole_key], loc="upper left", fontsize=8)
    frames = np.unique(np.linspace(0, len(replay.t) - 1, min(max_frames, len(replay.t)))
                       .astype(int))
    writer = PillowWriter(fps=fps)
    tmp = os.path.join(os.path.dirname(os.path.abspath(path)), f".tmp-{os.getpid()}.gif")
    try:
        with writer.saving(fig, tmp, dpi):
            for k in frames:
                ch, f = replay.chain[k], replay.flange_index
                arm.set_data_3d(ch[:f + 1, 0], ch[:f + 1, 1], ch[:f + 1, 2])
                club.set_data_3d(ch[f:, 0], ch[f:, 1], ch[f:, 2])
                trail.set_data_3d(replay.ball[:k + 1, 0], replay.ball[:k + 1, 1],
                                  replay.ball[:k + 1, 2])
                ball.set_data_3d(replay.ball[k:k + 1, 0], replay.ball[k:k + 1, 1],
                                 replay.ball[k:k + 1, 2])
                ax.set_title(f"{replay.field}: the {replay.robot}, {replay.label}\n"
                             f"t = {replay.t[k]:.2f} s, alpha = "
                             f"{replay.row['alpha_deg']:.2f} deg, kappa = "
                             f"{replay.row['kappa']:.3f}", fontsize=10)
                writer.grab_frame()
        os.chmod(tmp, 0o644 & ~umask())
        raise_pending_interrupt()  # a signal's interrupt first: nothing written after it
        os.replace(tmp, path)
    finally:
        plt.close(fig)
        if os.path.exists(tmp):
            os.unlink(tmp)
    return os.fspath(path)


def write_replay(scene: Scene, shots: list[Shot], out: str | os.PathLike, gif: bool = True,
                 fps: float = 25.0, max_time: float = 8.0, progress=None) -> dict:
    """Replay ``shots`` of one scene into ``out``: ``replay.html`` with all of them and, with
    ``gif``, one GIF per shot.

    Parameters
    ----------
    scene : Scene
    shots : list of Shot
    progress : callable, optional
        Called with a message before each shot (e.g. a logger's ``info``).

    Returns
    -------
    dict
        ``html`` (the page's path), ``gifs`` (paths), ``replays`` (the :class:`Replay` objects).
    """
    if not shots:
        raise ValueError("no shots to replay: give at least one shot")
    os.makedirs(out, exist_ok=True)
    fld = scene.field
    replays, gifs = [], []
    for i, shot in enumerate(shots):
        if progress:
            progress(f"replay {i + 1}/{len(shots)}: simulating {shot.method} shot "
                     f"{shot.index} again")
        replays.append(replay_shot(scene, shot, fps, max_time))
        if gif:
            gifs.append(write_replay_gif(replays[-1], fld, os.path.join(
                out, f"replay_{shot.method}_{shot.index}.gif")))
    html = write_replay_html(replays, fld, os.path.join(out, "replay.html"))
    return {"html": html, "gifs": gifs, "replays": replays}
