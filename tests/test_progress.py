"""Progress of long loops (seds_casadi.minigolf._progress): bars on a terminal, log lines
elsewhere, nothing when disabled; and the command line shows the lines, --quiet hides them."""

import io
import logging

import pytest

from seds_casadi.minigolf import _progress
from seds_casadi.minigolf._progress import progress_bar


@pytest.fixture()
def fast_clock(monkeypatch):
    """A clock that advances 4 s per reading: lines are due every few items."""
    t = [0.0]

    def clock():
        t[0] += 4.0
        return t[0]

    monkeypatch.setattr(_progress.time, "perf_counter", clock)


def test_without_a_terminal_progress_is_plain_log_lines(fast_clock, caplog):
    caplog.set_level(logging.INFO, logger="seds_casadi.progress")
    out = list(progress_bar(range(12), True, desc="teacher on flat", unit="situation"))
    assert out == list(range(12))
    lines = [r.getMessage() for r in caplog.records if r.name == "seds_casadi.progress"]
    assert lines and all(m.startswith("teacher on flat: ") for m in lines)
    assert all("\r" not in m and "\x1b" not in m for m in lines)   # no bar codes in a log
    counts = [int(m.split(": ")[1].split("/")[0]) for m in lines]
    assert counts == sorted(counts) and counts[-1] == 12 and "/12 situations" in lines[-1]


def test_disabled_progress_says_nothing(fast_clock, caplog, capsys):
    caplog.set_level(logging.INFO, logger="seds_casadi.progress")
    assert list(progress_bar(range(5), False, desc="x")) == list(range(5))
    bar = progress_bar(None, False, total=3, desc="y")
    bar.update(3)
    bar.close()
    assert not [r for r in caplog.records if r.name == "seds_casadi.progress"]
    assert capsys.readouterr().err == ""


def test_update_interface_without_a_terminal(fast_clock, caplog):
    caplog.set_level(logging.INFO, logger="seds_casadi.progress")
    bar = progress_bar(None, True, total=4, desc="LASA fits", unit="fit")
    for _ in range(4):
        bar.update(1)
    bar.close()
    bar.close()   # closing twice says it once
    lines = [r.getMessage() for r in caplog.records if r.name == "seds_casadi.progress"]
    assert lines[-1].startswith("LASA fits: 4/4 fits")
    assert sum(m.startswith("LASA fits: 4/4") for m in lines) == 1


def test_a_short_loop_logs_nothing(caplog):
    caplog.set_level(logging.INFO, logger="seds_casadi.progress")
    assert sum(progress_bar(range(100), True, desc="quick")) == 4950
    assert not [r for r in caplog.records if r.name == "seds_casadi.progress"]


def test_the_command_line_prints_progress_lines_and_quiet_hides_them(fast_clock, monkeypatch):
    from seds_casadi.app.cli import command_logging

    for quiet, shown in ((False, True), (True, False)):
        buf = io.StringIO()
        monkeypatch.setattr("sys.stdout", buf)
        with command_logging(quiet=quiet):
            list(progress_bar(range(6), True, desc="playing 6 shots", unit="shot"))
        assert ("playing 6 shots: 6/6 shots" in buf.getvalue()) is shown
