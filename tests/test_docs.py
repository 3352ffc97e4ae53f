"""The documentation site (docs/) builds with Sphinx with warnings as errors, and its API
reference documents every public name of ``seds_casadi`` and of its layers."""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"

pytest.importorskip("sphinx", reason="the docs extra is not installed: pip install '.[docs]'")


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """The site built once: ``python -m sphinx -W -b html docs OUT`` (examples not run)."""
    out = tmp_path_factory.mktemp("site")
    env = {k: v for k, v in os.environ.items() if k != "SEDS_DOCS_RUN_EXAMPLES"}
    env["MPLBACKEND"] = "Agg"
    res = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
         "-d", str(out / "doctrees"), str(DOCS), str(out / "html")],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=900)
    assert res.returncode == 0, (res.stdout + res.stderr)[-5000:]
    return out / "html"


def test_the_site_builds_with_warnings_as_errors(site):
    assert (site / "index.html").exists()
    assert (site / "auto_examples" / "index.html").exists()


def test_the_api_reference_documents_every_public_name(site):
    sys.path.insert(0, str(DOCS / "_ext"))
    try:
        from seds_api import documented_paths
    finally:
        sys.path.remove(str(DOCS / "_ext"))
    anchors = set()
    for page in (site / "api").glob("*.html"):
        anchors |= set(re.findall(r'id="(seds_casadi\.[\w.]+)"', page.read_text(encoding="utf-8")))
    paths = documented_paths()
    assert len(paths) > 200
    missing = sorted(p for p, target in paths.items()
                     if target not in anchors and not p.endswith("__version__"))
    assert not missing, f"public names without an entry in the API reference: {missing}"


def test_every_example_has_a_gallery_page(site):
    for script in sorted((ROOT / "examples").glob("*.py")):
        assert (site / "auto_examples" / f"{script.stem}.html").exists(), script.name
