"""The examples' gallery without running the examples.

sphinx-gallery builds a page per script of ``examples/`` (its docstring, its code). When the
examples are not run (the default, and in CI), this extension puts the figure the example draws,
saved in ``docs/`` by an earlier run, on its page and on its thumbnail, and gives every page a
title (the docstring's first sentence). ``EXAMPLE_FIGURES`` says which figure is whose.
"""

from __future__ import annotations

import re
from pathlib import Path

DOCS = Path(__file__).resolve().parents[1]
#: example script (stem) -> figures in docs/ it draws (written by the script at its full size)
EXAMPLE_FIGURES = {
    "quickstart": ["quickstart.png"],
    "fig2_target_field": ["fig2_target_field.png"],
    "fig3_rotated_hits": ["fig3_rotated_hits.png"],
    "fig4a_success_map": ["fig4a_strategies.png"],
    "fig6_reproductions": ["fig6_reproductions.png"],
    "fig7_robot_swings": ["fig7_robot_swings.png"],
    "fig8_perturbations": ["fig8_perturbations.png"],
    "joint_space_seds": ["joint_space_seds.png"],
    "pc_gmm": ["pc_gmm_JShape.png"],
    "direction_speeds": ["direction_speeds.png"],
    "choose_settings": ["choose_settings.png"],
    "model_selection": ["model_selection.png"],
    "katana_experiment": ["katana_experiment.png"],
    "table1_gpr_vs_gmr": ["table1_gpr_vs_gmr.png"],
    "table2_robot": ["table2_robot.png"],
}


class ExampleArgv:
    """The examples' own options when the gallery runs them (sphinx-gallery's ``reset_argv``):
    ``--quick`` if asked, and a figure file outside the source tree (sphinx-gallery collects
    the open figures itself). A class, not a function, so that Sphinx can cache the setting."""

    def __init__(self, quick: bool = False):
        self.quick = quick

    def __call__(self, gallery_conf, script_vars) -> list[str]:
        stem = Path(script_vars["src_file"]).stem
        out = Path(script_vars["target_file"]).parent / "_figures" / f"{stem}.png"
        return (["--quick"] if self.quick else []) + ["--out", str(out)]

    def __repr__(self) -> str:
        return f"ExampleArgv(quick={self.quick})"


def _figures(stem: str) -> list[Path]:
    return [DOCS / f for f in EXAMPLE_FIGURES.get(stem, []) if (DOCS / f).exists()]


def _place_thumbnails(app) -> None:
    """Before sphinx-gallery runs: each example's thumbnail from its saved figure (sphinx-gallery
    keeps a thumbnail that exists when the example itself made no figure)."""
    from sphinx_gallery.gen_rst import scale_image

    thumbs = DOCS / app.config.sphinx_gallery_conf["gallery_dirs"] / "images" / "thumb"
    thumbs.mkdir(parents=True, exist_ok=True)
    examples = Path(app.config.sphinx_gallery_conf["examples_dirs"])
    for script in sorted(examples.glob("*.py")):
        figs = _figures(script.stem)
        thumb = thumbs / f"sphx_glr_{script.stem}_thumb.png"
        if figs and (not thumb.exists() or thumb.stat().st_mtime < figs[0].stat().st_mtime):
            scale_image(str(figs[0]), str(thumb), 400, 280)


#: a full stop after these does not end a sentence
_ABBREVIATIONS = ("Fig", "Figs", "Eq", "Eqs", "Sec", "e.g", "i.e", "vs", "cf")


def _page_title(first_paragraph: str, limit: int = 64) -> str:
    """The docstring's first sentence, without "Paper " before a figure's or table's number;
    a long one up to its colon ("Choosing SEDS's settings: ..."), or cut at a word near
    ``limit`` characters."""
    text = " ".join(first_paragraph.split())
    end = len(text)
    for m in re.finditer(r"\.(\s|$)", text):
        if not text[: m.start()].endswith(_ABBREVIATIONS):
            end = m.start()
            break
    title = text[:end].strip().removeprefix("Paper ")
    head, colon, _ = title.partition(": ")
    if len(title) > limit and colon and len(head) >= 8 and not head.startswith(("Fig", "Table")):
        title = head
    if len(title) > limit:
        title = title[:limit].rsplit(" ", 1)[0].rstrip(",;:") + " ..."
    return title


def _literal_commands(text: str) -> str:
    """The docstring's ``python examples/...`` synopsis as a shell block, not a paragraph."""
    out = []
    for para in text.split("\n\n"):
        if para.lstrip().startswith("python "):
            body = "\n".join("   " + line for line in para.strip("\n").splitlines())
            para = ".. code-block:: bash\n\n" + body
        out.append(para)
    return "\n\n".join(out)


def _executed(app, stem: str) -> bool:
    """Whether sphinx-gallery runs this example in this build."""
    conf = app.config.sphinx_gallery_conf
    script = Path(conf["examples_dirs"]) / f"{stem}.py"
    return bool(conf.get("plot_gallery") and re.search(conf["filename_pattern"], str(script)))


def _example_page(app, docname: str, source: list[str]) -> None:
    """A title, the script's name and, when not run, its saved figure on each example's page."""
    gallery = app.config.sphinx_gallery_conf["gallery_dirs"]
    if not docname.startswith(gallery + "/") or docname.endswith("/index"):
        return
    stem = docname.split("/", 1)[1]
    text = source[0]
    # the docstring starts after sphinx-gallery's label and ends at its first code block
    m = re.search(r"^\.\. _sphx_glr_\S+:\n\n", text, flags=re.M)
    if not m:
        return
    start = m.end()
    end = text.find("\n.. GENERATED FROM PYTHON SOURCE LINES", start)
    head, rest = text[start:end], text[end:]
    first, _, more = head.partition("\n\n")
    title = _page_title(first)
    lines = [title, "=" * len(title), "", f"``examples/{stem}.py``", "", first, "",
             _literal_commands(more.rstrip()), ""]
    if not _executed(app, stem):
        for fig in _figures(stem):
            lines += [f".. figure:: /{fig.name}", "   :width: 100%", "",
                      f"   The figure ``examples/{stem}.py`` draws (saved in ``docs/{fig.name}``).",
                      ""]
    source[0] = text[:start] + "\n".join(lines) + rest


def setup(app):
    app.connect("builder-inited", _place_thumbnails, priority=400)
    app.connect("source-read", _example_page)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
