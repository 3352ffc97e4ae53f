"""The Python blocks of the README and of the documentation's pages run as written, in order,
one fresh interpreter per file (the README first, then each page of docs/ that has blocks)."""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]


def doc_files() -> list[Path]:
    """README.md and the hand-written pages of docs/ (not the build, not the generated gallery)."""
    docs = ROOT / "docs"
    pages = sorted(p for p in docs.rglob("*.md")
                   if not {"_build", "auto_examples"} & set(p.relative_to(docs).parts))
    return [ROOT / "README.md", *pages]


def python_blocks(path: Path) -> list[str]:
    """The ```python blocks of a Markdown file, in order."""
    return re.findall(r"```python\n(.*?)```", path.read_text(encoding="utf-8"), flags=re.S)


FILES = [p for p in doc_files() if python_blocks(p)]


def test_the_readme_and_the_tutorial_have_python_blocks():
    assert python_blocks(ROOT / "README.md")
    assert len(python_blocks(ROOT / "docs" / "getting_started.md")) >= 8


def test_the_readme_is_a_front_page_of_at_most_250_lines():
    lines = (ROOT / "README.md").read_text(encoding="utf-8").splitlines()
    assert len(lines) <= 250, f"README.md has {len(lines)} lines: move detail into docs/"


def test_relative_links_of_the_readme_and_the_pages_exist():
    """``[text](path)`` and ``<img src="path">`` links that are not URLs point at files."""
    broken = []
    for page in doc_files():
        text = page.read_text(encoding="utf-8")
        for target in re.findall(r"\]\(([^)\s]+)\)", text) + re.findall(r'src="([^"]+)"', text):
            if re.match(r"[a-z]+:", target) or target.startswith("#"):
                continue
            path = (page.parent / target.split("#")[0]).resolve()
            if not path.exists():
                broken.append(f"{page.relative_to(ROOT)}: {target}")
    assert not broken, broken


@pytest.mark.parametrize("path", FILES, ids=[str(p.relative_to(ROOT)) for p in FILES])
def test_every_python_block_runs_in_order(path, tmp_path):
    blocks = python_blocks(path)
    script = "\n\n".join(f"# --- {path.name} block {i}\n{b}" for i, b in enumerate(blocks))
    (tmp_path / "blocks.py").write_text(script, encoding="utf-8")
    env = dict(os.environ, MPLBACKEND="Agg")
    res = subprocess.run([sys.executable, "blocks.py"], cwd=tmp_path, env=env,
                         capture_output=True, text=True, timeout=900)
    assert res.returncode == 0, res.stderr[-3000:]
