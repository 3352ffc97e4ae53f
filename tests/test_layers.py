"""The package's layers: lower layers never import higher ones, and the SEDS core loads without
the optional extras (Pinocchio, exudyn, Dask)."""

import ast
import subprocess
import sys
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[1] / "seds_casadi"
#: what each layer may import (besides itself); the order of the README's architecture section
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
