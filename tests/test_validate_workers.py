"""validate --quick --workers: the same shots on worker processes as in this process."""

import csv
import subprocess
import sys

import numpy as np
import pytest

pytestmark = pytest.mark.slow

pytest.importorskip("exudyn")

from seds_casadi.app.validate import VALIDATION_COLUMNS, ValidateConfig, validate  # noqa: E402


def test_quick_validation_on_two_workers_equals_one(tmp_path):
    one = validate(ValidateConfig(field="flat", quick=True, out=str(tmp_path / "one"),
                                  progress=False))
    two = validate(ValidateConfig(field="flat", quick=True, workers=2,
                                  out=str(tmp_path / "two"), progress=False))
    assert len(one) == len(two) == 3   # --quick caps the shots
    for a, b in zip(one, two):
        assert set(a) == set(VALIDATION_COLUMNS)
        for c in VALIDATION_COLUMNS:
            if isinstance(a[c], float):
                assert np.isclose(a[c], b[c], equal_nan=True), c
            else:
                assert a[c] == b[c], c
    assert (tmp_path / "two" / "models" / "motion" / "stable_ds.npz").exists()
    with open(tmp_path / "two" / "validation.csv") as fh:
        assert tuple(next(csv.reader(fh))) == VALIDATION_COLUMNS


def test_validate_options_on_the_command_line(tmp_path):
    with pytest.raises(ValueError, match="workers"):
        ValidateConfig(workers=0)
    r = subprocess.run([sys.executable, "-m", "seds_casadi", "validate", "--help"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0
    for word in ("--quick", "--workers", "wam, katana, panda"):
        assert word in " ".join(r.stdout.split()), word
