"""The README's Python blocks run as written, in order, in one fresh interpreter."""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]


def readme_blocks() -> list[str]:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    return re.findall(r"```python\n(.*?)```", text, flags=re.S)


def test_the_readme_has_python_blocks():
    assert len(readme_blocks()) >= 4


def test_every_readme_python_block_runs_in_order(tmp_path):
    script = "\n\n".join(f"# --- README block {i}\n{b}" for i, b in enumerate(readme_blocks()))
    (tmp_path / "readme_blocks.py").write_text(script, encoding="utf-8")
    env = dict(os.environ, MPLBACKEND="Agg")
    res = subprocess.run([sys.executable, "readme_blocks.py"], cwd=tmp_path, env=env,
                         capture_output=True, text=True, timeout=900)
    assert res.returncode == 0, res.stderr[-3000:]
