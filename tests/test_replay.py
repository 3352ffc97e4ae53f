"""Replays (seds_casadi.app.replay): real swings on Pinocchio, the ball model, the page drawn in a
real headless Chromium, the GIF written by Pillow."""

import json
import os
import re
import shutil
import subprocess

import numpy as np
import pytest

pytestmark = pytest.mark.slow

pytest.importorskip("pinocchio")

from seds_casadi.app.cli import build_parser  # noqa: E402
from seds_casadi.app.play import PlayConfig  # noqa: E402
from seds_casadi.app.replay import (  # noqa: E402
    REPLAY_COLOURS,
    replay_shot,
    write_replay,
)
from seds_casadi.game.scene import Scene  # noqa: E402
from seds_casadi.game.shot import Shot, play_shot  # noqa: E402
from seds_casadi.minigolf.fields import load_field  # noqa: E402
from seds_casadi.minigolf.stroke import Stroke  # noqa: E402
from seds_casadi.motion import HittingMotionLearner, load_hitting_demos  # noqa: E402


@pytest.fixture(scope="module")
def motion_dir(tmp_path_factory):
    motion = HittingMotionLearner(n_components=3).fit(load_hitting_demos()).motion_
    folder = tmp_path_factory.mktemp("motion") / "motion"
    motion.save(str(folder))
    return str(folder), motion


def _scene(motion_dir, robot="wam"):
    folder, motion = motion_dir
    return Scene(robot, load_field("arctan"), motion, motion_folder=folder)


def _shot(motion_dir, ball=(0.1, -0.2), index=0):
    _, motion = motion_dir
    fld = load_field("arctan")
    s = np.asarray(fld.hole) - np.asarray(ball)
    alpha = float(Stroke.from_motion(motion).aim(s[None])[0])   # straight at the hole
    return Shot(ball, fld.hole, alpha, 1.1, method="gpr", index=index)


@pytest.fixture(scope="module")
def written(motion_dir, tmp_path_factory):
    out = tmp_path_factory.mktemp("replay")
    shots = [_shot(motion_dir), _shot(motion_dir, ball=(0.2, 0.3), index=1)]
    return out, shots, write_replay(_scene(motion_dir), shots, str(out), max_time=4.0)


def _segment_lengths(chain):
    return np.linalg.norm(np.diff(chain, axis=1), axis=2)


def test_a_replay_is_the_shot_play_played(motion_dir):
    shot = _shot(motion_dir)
    played = play_shot(_scene(motion_dir), shot)
    r = replay_shot(_scene(motion_dir), shot)
    assert r.row["sunk"] == played.sunk and r.row["hit"] and played.hit
    assert r.row["final_x_m"] == pytest.approx(played.final_position[0], abs=1e-12)
    row = {"final_x_m": played.final_position[0], "final_y_m": played.final_position[1]}
    task = {"ball": shot.ball}
    # the ball waits at its place until the hit, then follows the ball model's path
    before = r.t < r.hit_time
    assert before.any() and (~before).any()
    assert np.allclose(r.ball[before, :2], task["ball"])
    assert np.linalg.norm(r.ball[-1, :2] - [row["final_x_m"], row["final_y_m"]]) < 0.05
    # the arm is rigid: every segment of its chain keeps its length through the swing
    L = _segment_lengths(r.chain)
    assert np.allclose(L, L[0], atol=1e-9)
    # the club head reaches the ball: within a ball radius and a bit at the hit
    k = int(np.argmin(abs(r.t - r.hit_time)))
    assert np.linalg.norm(r.chain[k, -1, :2] - task["ball"]) < 0.06
    # the club is as long as the robot's club, and the frames are equally spaced
    assert L[0, r.flange_index] == pytest.approx(0.5, abs=1e-9)
    assert np.allclose(np.diff(r.t), 1 / 25)


def test_the_html_page_is_self_contained_and_carries_every_shot(written):
    out, shots, res = written
    page = open(res["html"], encoding="utf-8").read()
    assert oct(os.stat(res["html"]).st_mode & 0o777) == oct(0o666 & ~_umask())
    # no network: no external script, style, image or link
    assert not re.search(r"(src|href)\s*=\s*[\"']?(https?:)?//", page)
    data = json.loads(re.search(r'<script id="replay-data" type="application/json">(.*?)'
                                r"</script>", page, re.S).group(1))
    assert [s["label"].split(" (")[0] for s in data["shots"]] == ["gpr shot 0", "gpr shot 1"]
    assert "wam" in data["title"] and "arctan" in data["title"]
    for s, r in zip(data["shots"], res["replays"]):
        assert np.allclose(s["chain"], r.chain, atol=1e-4)
        assert len(s["t"]) == len(s["ball"]) == len(s["chain"])


def test_the_gifs_show_the_robot(written):
    from PIL import Image

    out, shots, res = written
    assert [os.path.basename(g) for g in res["gifs"]] == ["replay_gpr_0.gif", "replay_gpr_1.gif"]
    with Image.open(res["gifs"][0]) as im:
        assert im.n_frames > 10
        im.seek(im.n_frames // 2)
        px = np.asarray(im.convert("RGB")).reshape(-1, 3).astype(int)
    assert _near(px, REPLAY_COLOURS["robot"], 40) > 30


def _umask():
    m = os.umask(0o022)
    os.umask(m)
    return m


def _near(px, rgb, tol):
    return int(np.sum(np.all(np.abs(px - np.array(rgb)) <= tol, axis=1)))


def _chromium():
    for name in ("chromium", "chromium-browser", "google-chrome"):
        if shutil.which(name):
            return shutil.which(name)
    if os.environ.get("CI"):
        pytest.fail("CI: Chromium is required for the replay test (.ci/run installs it)")
    pytest.skip("Chromium not installed (apt-get install chromium); CI runs this test")


def test_the_page_draws_the_robot_and_the_field_in_headless_chromium(written, tmp_path):
    from PIL import Image

    out, shots, res = written
    shot = tmp_path / "replay.png"
    cmd = [_chromium(), "--headless", "--no-sandbox", "--disable-gpu",
           "--disable-background-networking", "--disable-component-update", "--disable-sync",
           "--no-first-run", f"--user-data-dir={tmp_path / 'profile'}",
           f"--screenshot={shot}", "--window-size=1000,700", "--virtual-time-budget=2000",
           "file://" + os.path.abspath(res["html"])]
    subprocess.run(cmd, capture_output=True, timeout=120, check=False)
    assert shot.exists(), "Chromium wrote no screenshot"
    px = np.asarray(Image.open(shot).convert("RGB")).reshape(-1, 3).astype(int)
    assert len(px) == 1000 * 700
    # the field fills a good part of the view, the arm is drawn in its colour, the canvas is
    # not a blank page
    field = sum(_near(px, np.array(REPLAY_COLOURS["field"]) * k, 14) for k in (0.7, 0.85, 1.0))
    assert field > 0.05 * len(px)
    assert _near(px, REPLAY_COLOURS["robot"], 20) > 300
    assert len(np.unique(px // 16, axis=0)) > 20


def test_bad_replay_requests_are_clear_errors(motion_dir, tmp_path):
    with pytest.raises(ValueError, match="no shots"):
        write_replay(_scene(motion_dir), [], str(tmp_path))
    with pytest.raises(ValueError, match="fps"):
        replay_shot(_scene(motion_dir), _shot(motion_dir), fps=0)
    with pytest.raises(ValueError, match="replay"):
        PlayConfig(replay=-1)
    with pytest.raises(ValueError, match="unknown robot 'no_such_arm'; known: wam, katana"):
        write_replay(_scene(motion_dir, "no_such_arm"), [_shot(motion_dir)], str(tmp_path))
    assert not (tmp_path / "replay.html").exists()


def test_play_replay_option():
    p = build_parser()
    assert p.parse_args(["play"]).replay == 0
    assert p.parse_args(["play", "--replay"]).replay == 1
    assert p.parse_args(["play", "--replay", "3"]).replay == 3
