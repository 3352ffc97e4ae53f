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
    env = {k: v for k, v in os.environ.items()
           if k not in ("SEDS_DOCS_RUN_EXAMPLES", "SEDS_DOCS_MATHJAX")}
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


def test_the_maths_renders_offline_from_the_sites_own_mathjax(site):
    """Every page with equations loads MathJax from the site (sphinx-mathjax-offline), never
    from a CDN: the site is read on machines without internet."""
    pages = {p: p.read_text(encoding="utf-8") for p in site.rglob("*.html")}
    maths = [p for p, text in pages.items() if 'class="math' in text]
    assert len(maths) >= 4  # the layers pages with the paper's equations
    for page in maths:
        srcs = re.findall(r'<script[^>]*src="([^"]*mathjax[^"]*)"', pages[page], re.I)
        assert srcs and all("//" not in s for s in srcs), (page, srcs)
    for page, text in pages.items():  # no page loads it from elsewhere
        assert not re.search(r'src="[^"]*//[^"]*mathjax', text, re.I), page
    assert (site / "_static" / "mathjax" / "tex-chtml.js").stat().st_size > 100_000


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
