"""The API reference, generated from the package's ``__all__`` lists.

``.. seds-api:: seds_casadi.core`` documents every name of the package's ``__all__`` and of the
``__all__`` of each of its modules that the package does not already list: a summary table, then
each name with autodoc (numpydoc formats the docstrings). An object is documented once, at the
first public path that lists it (a package before its modules; ``seds_casadi`` itself, whose
names all come from the core, links to the core's entries). :func:`public_names` is what
``tests/test_docs.py`` checks the built site against.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import re

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.pycode import ModuleAnalyzer
from sphinx.util.docutils import SphinxDirective
from sphinx.util.nodes import nested_parse_with_titles

PACKAGE = "seds_casadi"
#: the layers in the README's order (lowest first)
LAYERS = ("core", "codegen", "motion", "minigolf", "robots", "sim", "game", "app")


def _modules(package: str) -> list[str]:
    """The package and its public modules (no leading underscore in any part, no __main__)."""
    mod = importlib.import_module(package)
    names = [package]
    if hasattr(mod, "__path__"):
        for info in pkgutil.walk_packages(mod.__path__, package + "."):
            parts = info.name.split(".")
            if any(p.startswith("_") for p in parts):
                continue
            names.append(info.name)
    return names


def public_names(package: str, seen: dict[int, str] | None = None) -> list[tuple[str, list[str]]]:
    """``[(module, [name, ...]), ...]``: the names of each ``__all__`` under ``package`` that an
    earlier entry (or ``seen``, id -> documented path) does not already document."""
    seen = {} if seen is None else seen
    out = []
    for modname in _modules(package):
        mod = importlib.import_module(modname)
        names = []
        for name in getattr(mod, "__all__", ()):
            obj = getattr(mod, name)
            key = id(obj)
            if not _is_value(obj) and key in seen:
                continue
            if not _is_value(obj):
                seen[key] = f"{modname}.{name}"
            names.append(name)
        if names:
            out.append((modname, names))
    return out


def _is_value(obj) -> bool:
    """Numbers, strings, tuples ...: identity says nothing about where they are documented."""
    return not (inspect.isclass(obj) or inspect.isroutine(obj) or inspect.ismodule(obj)
                or callable(obj))


def documented_paths() -> dict[str, str]:
    """Every public path ``module.name`` -> the path its documentation is under."""
    seen: dict[int, str] = {}
    paths = {}
    for layer in LAYERS:
        for modname, names in public_names(f"{PACKAGE}.{layer}", seen):
            for name in names:
                paths[f"{modname}.{name}"] = f"{modname}.{name}"
    top = importlib.import_module(PACKAGE)
    for name in top.__all__:
        obj = getattr(top, name)
        paths[f"{PACKAGE}.{name}"] = seen.get(id(obj), f"{PACKAGE}.{name}")
    return paths


def _attr_doc(modname: str, name: str, obj) -> list[str]:
    """The ``#:`` comment of a module-level value, looked up in the module and its siblings."""
    candidates = [modname] + [m for m in _modules(modname) if m != modname]
    for cand in candidates:
        mod = importlib.import_module(cand)
        if getattr(mod, name, None) is not obj:
            continue
        try:
            docs = ModuleAnalyzer.for_module(cand).find_attr_docs()
        except Exception:  # no source
            continue
        if ("", name) in docs:
            return list(docs[("", name)])
    return []


def _entry(modname: str, name: str, obj) -> list[str]:
    full = f"{modname}.{name}"
    if inspect.isclass(obj):
        if issubclass(obj, BaseException):
            return [f".. autoexception:: {full}", ""]
        return [f".. autoclass:: {full}", "   :members:", ""]
    if inspect.isroutine(obj) or callable(obj):
        return [f".. autofunction:: {full}", ""]
    lines = [f".. autodata:: {full}"]
    if len(repr(obj)) > 70:
        lines.append("   :no-value:")
    doc = _attr_doc(modname, name, obj)
    lines.append("")
    lines += ["   " + d if d.strip() else "" for d in doc]
    if not doc:
        lines.append(f"   The value of ``{name}`` ({type(obj).__name__}).")
    lines.append("")
    return lines


class PublicAPI(SphinxDirective):
    """``.. seds-api:: PACKAGE``: the package's public names, each documented once."""

    required_arguments = 1
    has_content = False

    def run(self) -> list[nodes.Node]:
        package = self.arguments[0]
        lines: list[str] = []
        if package == PACKAGE:
            lines += self._top_level()
        else:
            seen = _seen_before(package)
            for modname, names in public_names(package, seen):
                lines += self._module_section(modname, names, package)
        content = StringList(lines, source=f"<seds-api {package}>")
        node = nodes.container()
        nested_parse_with_titles(self.state, content, node)
        return node.children

    @staticmethod
    def _module_section(modname: str, names: list[str], package: str) -> list[str]:
        mod = importlib.import_module(modname)
        lines = []
        if modname != package:
            title = f"``{modname}``"
            lines += [title, "-" * len(title), ""]
        lines += [f".. automodule:: {modname}", "   :no-members:", "",
                  f".. currentmodule:: {modname}", "", ".. autosummary::",
                  "   :nosignatures:", ""]
        lines += [f"   {n}" for n in names]
        lines.append("")
        for n in names:
            lines += _entry(modname, n, getattr(mod, n))
        return lines

    @staticmethod
    def _top_level() -> list[str]:
        paths = documented_paths()
        top = importlib.import_module(PACKAGE)
        lines = [".. automodule:: seds_casadi", "   :no-members:", "",
                 "The names ``seds_casadi`` gathers (each documented in its layer):", "",
                 ".. list-table::", "   :header-rows: 1", "", "   * - name", "     - documented as", ""]
        for name in top.__all__:
            target = paths[f"{PACKAGE}.{name}"]
            if name == "__version__":
                where = f"the package's version, ``{top.__version__}``"
            else:
                where = f":py:obj:`{target}`"
            lines += [f"   * - ``seds_casadi.{name}``", f"     - {where}"]
        lines.append("")
        return lines


def _seen_before(package: str) -> dict[int, str]:
    """Objects documented by the layers before ``package`` (the order of LAYERS)."""
    seen: dict[int, str] = {}
    layer = package.split(".")[1]
    for other in LAYERS[: LAYERS.index(layer)]:
        public_names(f"{PACKAGE}.{other}", seen)
    return seen


_LITERAL = re.compile(r"(``.+?``|:[a-z:]+:`[^`]+`|`[^`]+`_?)")
_STAR = re.compile(r"(?<![\w*\\`])(\*{1,2})(?=[\w(])(?![^*\n]*[^\s*]\*)")


def _escape_plain(text: str) -> str:
    """``|x|`` and ``*args`` as a reader means them, outside inline literals and roles."""
    parts = _LITERAL.split(text)
    for i in range(0, len(parts), 2):  # the even parts are outside literals
        parts[i] = parts[i].replace("|", "\\|")
        parts[i] = _STAR.sub(lambda m: "\\*" * len(m.group(1)), parts[i])
    return "".join(parts)


def escape_plain_text_math(app, what, name, obj, options, lines: list[str]) -> None:
    """The docstrings write maths in plain text (``|f(x)|``, ``x*``, ``*args``); reStructuredText
    would read ``|...|`` as a substitution and ``*...`` as emphasis. Escape them, except in
    literal blocks (after ``::``), doctests and tables."""
    literal_indent = None
    previous = ""
    for k, line in enumerate(lines):
        stripped = line.lstrip()
        indent = len(line) - len(stripped)
        if literal_indent is not None:
            if stripped and indent <= literal_indent:
                literal_indent = None
            else:
                previous = line
                continue
        if previous.rstrip().endswith("::") and not stripped:
            literal_indent = len(previous) - len(previous.lstrip())
            previous = line
            continue
        if previous.rstrip().endswith("::") and indent > len(previous) - len(previous.lstrip()):
            literal_indent = len(previous) - len(previous.lstrip())
            previous = line
            continue
        if not (stripped.startswith((">>>", "... ", "| ", "+-", "+=", "==")) or stripped == "|"):
            lines[k] = line[:indent] + _escape_plain(stripped)
        previous = line


def skip_foreign_members(app, what, name, obj, skip, options):
    """Skip members a class gets from scikit-learn (the metadata-routing ``set_*_request``)."""
    module = getattr(obj, "__module__", None) or ""
    if what == "class" and module.startswith("sklearn"):
        return True
    return None


#: abbreviations after which autosummary's first sentence goes on ("... system (Eq. 5-7).")
ABBREVIATIONS = ("Eq.", "Eqs.", "Fig.", "Figs.", "Sec.", "cf.", "vs.", "approx.")


def setup(app):
    from sphinx.ext import autosummary

    autosummary.WELL_KNOWN_ABBREVIATIONS = (*autosummary.WELL_KNOWN_ABBREVIATIONS, *ABBREVIATIONS)
    app.add_directive("seds-api", PublicAPI)
    app.connect("autodoc-process-docstring", escape_plain_text_math, priority=400)
    app.connect("autodoc-skip-member", skip_foreign_members)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
