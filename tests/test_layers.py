"""The package's architecture as tests: imports point down the layers, no cycles, small modules.

The layers, bottom first (docs/development.md); a module may import from its own
package or from a lower layer.  The few upward imports are lazy delegates,
listed by name below, each a method that hands its work to a higher layer.
"""

import ast
import inspect
from pathlib import Path

import pytest

import hht3d

PACKAGE = Path(hht3d.__file__).parent
LAYERS = [
    ("hht3d.redaction", "hht3d.open3d_quiet"),
    ("hht3d.logs",),
    ("hht3d.errors", "hht3d.version"),
    ("hht3d.records",),
    ("hht3d.linalg",),
    ("hht3d.geometry",),
    ("hht3d.io",),
    ("hht3d.decomposition",),
    ("hht3d.spectral",),
    ("hht3d.hht_options",),
    ("hht3d.transform",),
    ("hht3d.results", "hht3d.apps", "hht3d.viz"),
    ("hht3d.output_formats",),
    ("hht3d.execution",),
    ("hht3d.graph",),
    ("hht3d.dataset",),
    ("hht3d.pipeline",),
    ("hht3d.stopping",),
    ("hht3d.cli",),
    ("hht3d.__main__",),
]
#: Upward imports inside a function: (importing module, imported module).
DELEGATES = {
    ("hht3d.transform", "hht3d.viz.viewer"),  # HHTResult.to_html
    ("hht3d.transform", "hht3d.viz.notebook"),  # HHTResult.show
    ("hht3d.geometry.surface", "hht3d.viz.notebook"),  # Surface._repr_html_ and Surface.show
    ("hht3d.transform", "hht3d.output_formats"),
}  # HHTResult.save
MAX_LINES = 400


def _modules() -> dict[str, Path]:
    names = {}
    for path in PACKAGE.rglob("*.py"):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        names[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return names


def _imports(name: str, path: Path, known) -> set[str]:
    """The hht3d modules ``name`` imports (a package's submodules count as the package's)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            base = package.rsplit(".", node.level - 1)[0] if node.level else ""
            target = ".".join(p for p in (base, node.module) if p)
            found |= {f"{target}.{a.name}" if f"{target}.{a.name}" in known else target for a in node.names}
        elif isinstance(node, ast.Import):
            found |= {a.name for a in node.names}
    return {t for t in found if t in known and t != name}


def _rank(name: str) -> int:
    """The layer of the longest prefix of ``name`` that LAYERS lists."""
    ranks = {top: i for i, group in enumerate(LAYERS) for top in group}
    return ranks[max((top for top in ranks if name == top or name.startswith(top + ".")), key=len)]


def _group(name: str) -> str:
    return ".".join(name.split(".")[:2])


GRAPH = {name: _imports(name, path, _modules()) for name, path in _modules().items() if name != "hht3d"}


def test_imports_point_down():
    upward = sorted(
        (name, target)
        for name, targets in GRAPH.items()
        for target in targets
        if _rank(target) > _rank(name) or (_rank(target) == _rank(name) and _group(target) != _group(name))
    )
    assert set(upward) <= DELEGATES, f"upward imports: {sorted(set(upward) - DELEGATES)}"


def test_no_import_cycle():
    """No cycle of imports made when a module loads: a delegate imports when its method runs, after every
    module it could reach has loaded (the formats a result is saved in import the result)."""
    state: dict[str, int] = {}

    def visit(name, trail):
        if state.get(name) == 1:
            pytest.fail("import cycle: " + " -> ".join(trail[trail.index(name) :] + [name]))
        if state.get(name) != 2:
            state[name] = 1
            for target in GRAPH.get(name, ()):
                if (name, target) not in DELEGATES:
                    visit(target, trail + [name])
            state[name] = 2

    for name in GRAPH:
        visit(name, [])


def test_modules_are_small():
    long = {name: n for name, path in _modules().items() if (n := len(path.read_text().splitlines())) > MAX_LINES}
    assert not long, f"modules over {MAX_LINES} lines: {long}"


def test_public_functions_are_plain_and_no_module_shares_their_name():
    for name in ("emd", "eemd", "riesz", "monogenic", "hht", "load", "fractional_laplacian"):
        assert inspect.isfunction(getattr(hht3d, name)), name
        assert not any(module.rpartition(".")[2] == name for module in _modules()), name
