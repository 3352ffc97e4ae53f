"""Output files get the mode a plain ``open`` would give them (0666 minus the umask), not the
0600 of the temporary file they are written through."""

import os
import stat

import numpy as np
import pytest

from seds_casadi.core._io import atomic_csv, atomic_npz, atomic_text


@pytest.mark.parametrize("mask", [0o022, 0o077, 0o002])
def test_atomic_writers_respect_the_umask(tmp_path, mask):
    old = os.umask(mask)
    try:
        atomic_text(tmp_path / "a.txt", "x\n")
        atomic_csv(tmp_path / "a.csv", ["alpha_deg"], [[1.5]])
        atomic_npz(tmp_path / "a.npz", x=np.arange(3))
        with open(tmp_path / "plain.txt", "w") as fh:   # what a plain open gives
            fh.write("x")
    finally:
        os.umask(old)
    want = stat.S_IMODE(os.stat(tmp_path / "plain.txt").st_mode)
    assert want == 0o666 & ~mask
    for name in ("a.txt", "a.csv", "a.npz"):
        assert stat.S_IMODE(os.stat(tmp_path / name).st_mode) == want, name
    assert (tmp_path / "a.csv").read_text() == "alpha_deg\n1.5\n"
    assert not [p for p in os.listdir(tmp_path) if p.startswith(".tmp-")]
