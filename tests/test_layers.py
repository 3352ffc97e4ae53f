"""The package's layers: lower layers never import higher ones, and the SEDS core loads without
the optional extras (Pinocchio, exudyn, Dask); one import path per public name, no private name
imported across modules, no import cycles."""

import ast
import re
import subprocess
import sys
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[1] / "seds_casadi"
#: what each layer may import (besides itself); the order of the architecture table in docs/layers
ALLOWED = {
    "codegen": set(),
    "core": {"codegen"},
    "motion": {"core", "codegen"},
    "minigolf": {"motion", "core", "codegen"},
    "robots": {"motion", "core", "codegen"},
    "sim": {"robots", "minigolf", "motion", "core", "codegen"},
    "game": {"sim", "robots", "minigolf", "motion", "core", "codegen"},
    "app": {"game", "sim", "robots", "minigolf", "motion", "core", "codegen"},
}


def _imported_layers(path: Path, layer: str) -> set[str]:
    """Layers of seds_casadi imported by a module (relative or absolute, also inside functions)."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level == 0:
                parts = (node.module or "").split(".")
                if parts[0] == "seds_casadi" and len(parts) > 1:
                    out.add(parts[1])
            else:
                # resolve the relative import against the module's package
                pkg = ["seds_casadi", *path.relative_to(PKG).parts[:-1]]
                base = pkg[: len(pkg) - (node.level - 1)]
                target = base + (node.module.split(".") if node.module else [])
                if len(target) > 1:
                    out.add(target[1])
                elif node.module is None:  # from .. import name
                    out.update(a.name for a in node.names)
        elif isinstance(node, ast.Import):
            for a in node.names:
                parts = a.name.split(".")
                if parts[0] == "seds_casadi" and len(parts) > 1:
                    out.add(parts[1])
    return {x for x in out if x in ALLOWED and x != layer}


@pytest.mark.parametrize("layer", sorted(ALLOWED))
def test_a_layer_imports_only_the_layers_below_it(layer):
    bad = {}
    for path in sorted((PKG / layer).rglob("*.py")):
        extra = _imported_layers(path, layer) - ALLOWED[layer]
        if extra:
            bad[str(path.relative_to(PKG))] = sorted(extra)
    assert not bad, f"imports from higher layers: {bad}"


def test_the_top_level_package_imports_only_the_core():
    assert _imported_layers(PKG / "__init__.py", "") <= {"core"}


def test_the_core_minigolf_and_motion_load_without_the_extras():
    code = ("import sys; import seds_casadi; from seds_casadi import SEDS; "
            "import seds_casadi.core, seds_casadi.motion, seds_casadi.minigolf, seds_casadi.app.cli; "
            "print(sorted(m for m in ('pinocchio', 'exudyn', 'distributed', 'dask') "
            "if m in sys.modules))")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == "[]"


def test_a_missing_extra_is_named_in_the_import_error():
    # hide pinocchio / exudyn from the import system and import the layers that need them
    for layer, hidden, extra in (("robots", "pinocchio", "robots"), ("sim", "exudyn", "sim")):
        code = (f"import sys; sys.modules[{hidden!r}] = None\n"
                f"try:\n    import seds_casadi.{layer}\nexcept ImportError as e:\n    print(e)")
        res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                             timeout=120)
        assert res.returncode == 0, res.stderr
        assert f"pip install 'seds_casadi[{extra}]'" in res.stdout, res.stdout


# ------------------------------------------------------------------ one import path per name
# Read from the source (ast), not from imported modules: a name has one import path, its defining
# module (or a package ``__init__`` above it); no private name is imported from another module;
# the modules import each other without cycles, counting imports inside functions.

ROOT = PKG.parent
#: files that import the package as users do: the tests, examples, benchmarks, and the code blocks
#: of the README and of the documentation's pages (docs/**/*.md)
USERS = ("tests", "examples", "benchmarks")

#: imports exempt from the checks, as (importing module, imported module, name): none since the
#: game layer landed; add one only with the reason beside it
GAME_LAYER_LEFTOVERS: set = set()


class _Module:
    """One module of a package, read with ast: what it defines and what it imports."""

    def __init__(self, name: str, path: Path, is_package: bool, tree: ast.Module) -> None:
        self.name, self.path, self.is_package, self.tree = name, path, is_package, tree
        self.defined: set[str] = set()
        self.all: list[str] | None = None
        self.has_getattr = False
        for node in _top_level(tree.body):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                self.defined.add(node.name)
                self.has_getattr |= node.name == "__getattr__"
            elif isinstance(node, (ast.Assign, ast.AnnAssign, ast.AugAssign)):
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                for t in targets:
                    self.defined.update(n.id for n in ast.walk(t) if isinstance(n, ast.Name))
                    if isinstance(t, ast.Name) and t.id == "__all__":
                        self.all = [ast.literal_eval(e) for e in node.value.elts]
            elif isinstance(node, ast.Import):  # `import numpy as np` binds np here
                self.defined.update((a.asname or a.name).split(".")[0] for a in node.names)

    def package(self) -> str:
        """The package a relative import starts from."""
        return self.name if self.is_package else self.name.rpartition(".")[0]


def _top_level(body):
    """The module's top-level statements, with those inside top-level ``if`` and ``try``."""
    for node in body:
        yield node
        if isinstance(node, (ast.If, ast.Try)):
            for block in (node.body, node.orelse, getattr(node, "handlers", []),
                          getattr(node, "finalbody", [])):
                for sub in block:
                    yield from _top_level(sub.body if isinstance(sub, ast.ExceptHandler)
                                          else [sub])


def _type_checking_nodes(tree: ast.Module) -> set[int]:
    """ids of the nodes inside ``if TYPE_CHECKING:`` blocks (annotations only, never run)."""
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for sub in node.body:
                out.update(id(n) for n in ast.walk(sub))
    return out


def _read_package(pkg_dir: Path) -> dict[str, _Module]:
    mods = {}
    for path in sorted(pkg_dir.rglob("*.py")):
        parts = [pkg_dir.name, *path.relative_to(pkg_dir).with_suffix("").parts]
        is_package = parts[-1] == "__init__"
        name = ".".join(parts[:-1] if is_package else parts)
        mods[name] = _Module(name, path, is_package, ast.parse(path.read_text()))
    return mods


def _imports(tree: ast.Module, importer: str, package: str | None, mods: dict[str, _Module]):
    """(imported module, name or None for a module, line, runs) of each import of the package:
    ``from X import n`` where ``n`` is a submodule counts as importing the submodule; ``runs`` is
    False inside ``if TYPE_CHECKING:``."""
    top = next(iter(mods)).split(".")[0]
    hidden = _type_checking_nodes(tree)
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                if package is None:
                    continue
                base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] != top:
                continue
            for a in node.names:
                sub = f"{target}.{a.name}"
                if sub in mods:
                    yield sub, None, node.lineno, id(node) not in hidden
                else:
                    yield target, a.name, node.lineno, id(node) not in hidden
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.split(".")[0] == top and a.name in mods:
                    yield a.name, None, node.lineno, id(node) not in hidden


def _user_trees(root: Path, users=USERS):
    """(label, tree) of the files that import the package as users: scripts, and the python code
    blocks of the README and of the documentation's Markdown pages."""
    for folder in users:
        for path in sorted((root / folder).rglob("*.py")):
            yield str(path.relative_to(root)), ast.parse(path.read_text())
    pages = [root / "README.md"]
    if (root / "docs").is_dir():  # the documentation's pages, as tests/test_readme.py runs them
        pages += sorted(p for p in (root / "docs").rglob("*.md")
                        if not {"_build", "auto_examples"} & set(p.relative_to(root).parts))
    for page in pages:
        if not page.exists():
            continue
        blocks = re.findall(r"```python\n(.*?)```", page.read_text(), flags=re.S)
        for k, code in enumerate(blocks):
            try:
                yield f"{page.relative_to(root)} (python block {k + 1})", ast.parse(code)
            except SyntaxError:
                continue


def _origin(mods: dict[str, _Module], module: str, name: str, seen=()) -> str | None:
    """The module that defines ``name`` as seen from ``module`` (following its imports)."""
    mod = mods.get(module)
    if mod is None or (module, name) in seen:
        return None
    if name in mod.defined:
        return module
    for target, n, _, _ in _imports(mod.tree, module, mod.package(), mods):
        if n == name:
            return _origin(mods, target, name, (*seen, (module, name)))
    return None


def _inside(module: str, package: str) -> bool:
    return module == package or module.startswith(package + ".")


def reexport_problems(pkg_dir: Path, root: Path | None = None, users=USERS,
                      allowed=frozenset()) -> list[str]:
    """Names with a second import path: a module (not a package ``__init__``) that lists in
    ``__all__`` a name it imports, or hands out names of other modules (module ``__getattr__``);
    a package ``__init__`` that exports a name defined outside its own subpackage; and any
    ``from M import n`` (in the package or its users) where ``M`` does not define ``n``
    (a package: ``n`` is not defined below it)."""
    mods = _read_package(pkg_dir)
    out = []
    for mod in mods.values():
        for n in mod.all or ():
            origin = _origin(mods, mod.name, n)
            if not mod.is_package and n not in mod.defined:
                out.append(f"{mod.name}: __all__ lists {n!r}, defined in {origin}")
            elif mod.is_package and origin is not None and not _inside(origin, mod.name):
                out.append(f"{mod.name}: __all__ lists {n!r}, defined outside it in {origin}")
        if mod.has_getattr and not mod.is_package:
            out.append(f"{mod.name}: a module __getattr__ hands out names")
    importers = [(m.name, m.tree, m.package()) for m in mods.values()]
    importers += [(label, tree, None) for label, tree in _user_trees(root, users)] if root else []
    for importer, tree, package in importers:
        for target, name, line, _ in _imports(tree, importer, package, mods):
            if name is None or target not in mods or (importer, target, name) in allowed:
                continue
            mod = mods[target]
            if name in mod.defined:
                continue
            origin = _origin(mods, target, name)
            if not mod.is_package or origin is None or not _inside(origin, target):
                out.append(f"{importer}:{line} imports {name!r} from {target}, defined in "
                           f"{origin}")
    return sorted(set(out))


def private_import_problems(pkg_dir: Path, allowed=frozenset()) -> list[str]:
    """``from X import _name`` in the package with X another of its modules."""
    mods = _read_package(pkg_dir)
    out = []
    for mod in mods.values():
        for target, name, line, _ in _imports(mod.tree, mod.name, mod.package(), mods):
            if (name and name.startswith("_") and not name.startswith("__")
                    and target != mod.name and (mod.name, target, name) not in allowed):
                out.append(f"{mod.name}:{line} imports {name} from {target}")
    return out


def import_cycles(pkg_dir: Path, allowed=frozenset()) -> list[list[str]]:
    """Import cycles among the package's modules (strongly connected components of more than
    one module), imports inside functions included, ``if TYPE_CHECKING:`` imports not.

    An import of ``a.b.c`` also runs the packages ``a.b`` and ``a`` (edges to them), except
    those the importer sits in already; a package ``__init__`` importing its own submodules is
    an edge like any other, so a submodule that imports its package back closes a cycle."""
    mods = _read_package(pkg_dir)
    graph: dict[str, set[str]] = {m: set() for m in mods}
    for mod in mods.values():
        for target, name, _, runs in _imports(mod.tree, mod.name, mod.package(), mods):
            if not runs or (mod.name, target, name) in allowed or target not in mods:
                continue
            parts = target.split(".")
            for k in range(1, len(parts) + 1):
                dep = ".".join(parts[:k])
                if dep != mod.name and dep in mods and (k == len(parts)
                                                        or not _inside(mod.name, dep)):
                    graph[mod.name].add(dep)
    # Tarjan's strongly connected components
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    cycles = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                cycles.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return cycles


def test_the_documentation_pages_code_blocks_are_checked_as_users():
    labels = [label for label, _ in _user_trees(ROOT)]
    assert any(label.startswith("README.md (python block") for label in labels)
    assert sum(label.startswith("docs/getting_started.md (python block") for label in labels) >= 8


def test_every_name_has_one_import_path():
    assert reexport_problems(PKG, ROOT, allowed=GAME_LAYER_LEFTOVERS) == []


def test_no_private_name_is_imported_from_another_module():
    assert private_import_problems(PKG, allowed=GAME_LAYER_LEFTOVERS) == []


def test_the_modules_import_each_other_without_cycles():
    assert import_cycles(PKG, allowed=GAME_LAYER_LEFTOVERS) == []


# the checkers on a small package of their own: each problem is found, and a clean package passes
_SYNTHETIC = {
    "__init__.py": "from .a import f\n__all__ = ['f']\n",
    "a.py": "def f():\n    pass\n\n\ndef _g():\n    pass\n",
    "b.py": "from .a import _g, f\n\n__all__ = ['f']\n",                 # re-export, private
    "c.py": "from .b import f\n",                                         # through b, not a
    "d.py": "def late():\n    from . import e\n",                        # d -> e, in a function
    "e.py": "from .d import late\n",                                      # e -> d: a cycle
    "t.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .u import U\n",
    "u.py": "from .t import TYPE_CHECKING\nclass U:\n    pass\n",         # no cycle via t
    "sub/__init__.py": "from ..a import f\nfrom .s import h\n__all__ = ['f', 'h']\n",
    "sub/s.py": "def h():\n    pass\n",
    "lazy.py": "def __getattr__(name):\n    from . import a\n    return getattr(a, name)\n",
}


def _write_package(tmp_path: Path, files: dict[str, str]) -> Path:
    pkg = tmp_path / "pkg"
    for rel, text in files.items():
        (pkg / rel).parent.mkdir(parents=True, exist_ok=True)
        (pkg / rel).write_text(text)
    return pkg


def test_the_checkers_find_each_problem_in_a_small_package(tmp_path):
    pkg = _write_package(tmp_path, _SYNTHETIC)
    (tmp_path / "scripts").mkdir()
    (tmp_path / "scripts" / "use.py").write_text("from pkg.b import f\nfrom pkg import f\n")
    problems = reexport_problems(pkg, tmp_path, users=("scripts",))
    assert problems == sorted([
        "pkg.b: __all__ lists 'f', defined in pkg.a",
        "pkg.c:1 imports 'f' from pkg.b, defined in pkg.a",
        "pkg.lazy: a module __getattr__ hands out names",
        "pkg.sub: __all__ lists 'f', defined outside it in pkg.a",
        "pkg.sub:1 imports 'f' from pkg, defined in pkg.a",
        "scripts/use.py:1 imports 'f' from pkg.b, defined in pkg.a",
    ]) or problems
    assert private_import_problems(pkg) == ["pkg.b:1 imports _g from pkg.a"]
    assert import_cycles(pkg) == [["pkg.d", "pkg.e"]]
    # an allowed import is skipped
    assert import_cycles(pkg, allowed={("pkg.d", "pkg.e", None)}) == []


def test_the_checkers_pass_a_clean_package(tmp_path):
    pkg = _write_package(tmp_path, {
        "__init__.py": "from .a import f\nfrom .sub import h\n__all__ = ['f', 'h']\n",
        "a.py": "import os\n\n__all__ = ['f']\n\n\ndef f():\n    return os.sep\n",
        "b.py": "from .a import f\nfrom .sub.s import h\n\n\ndef g():\n    from . import c\n"
                "    return f, h, c\n",
        "c.py": "from .a import f\n",
        "sub/__init__.py": "from .s import h\n__all__ = ['h']\n",
        "sub/s.py": "def h():\n    pass\n",
    })
    assert reexport_problems(pkg, tmp_path, users=()) == []
    assert private_import_problems(pkg) == []
    assert import_cycles(pkg) == []


def test_a_submodule_importing_its_own_package_is_a_cycle(tmp_path):
    pkg = _write_package(tmp_path, {"__init__.py": "from .a import f\n",
                                    "a.py": "def f():\n    from . import VERSION\n",
                                    "v.py": ""})
    assert import_cycles(pkg) == [["pkg", "pkg.a"]]
