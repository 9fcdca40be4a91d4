"""The import rule as a test: every package imports only from layers below it, and no module
takes part in an import cycle. Module-level and function-level imports count alike."""

from __future__ import annotations

import ast
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent

# Higher imports lower, as DESIGN.md draws the folders. mobot_cli/__init__.py (the version),
# mobot_cli/errors.py, mobot_cli/plan.py (the Plan every layer passes down) and mobot_cli/plan_json.py
# (a Plan as JSON) sit below everything;
# mobot_cli/__main__.py is the entry point above everything.
LAYERS = {
    "cli": 8,
    "run": 7, "live": 7, "sweep": 7, "api": 7, "gym": 7, "view": 7, "ros2": 7,  # the doors
    "record": 6,  # the run folder
    "ros": 5,  # ROS formats: the timeline's records as messages
    "timeline": 4,  # the one loop
    "scenario": 3,
    "assets": 2,
    "sim": 1,
    "common": 0,
}
BOTTOM = {"", "errors", "plan", "plan_json"}  # the package itself, mobot_cli.errors, mobot_cli.plan (and its JSON)
TOP = {"__main__"}
# The only imports between two packages of the same layer, each one way.
SAME_LAYER = {("live", "run"), ("sweep", "run"), ("api", "run"), ("gym", "api"), ("ros2", "run"), ("view", "run"),
              ("ros2", "live")}  # ros2/sim_services.py: the simulation_interfaces services are live clients


def module_name(root: Path, path: Path) -> str:
    """The dotted name of a source file below ``root`` (a package's __init__ is the package)."""
    parts = list(path.relative_to(root).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports(root: Path, package: str = "mobot_cli"):
    """(file, line, importer, imported) for every import of ``package`` below ``root``, at any depth
    of the code; ``imported`` is the module imported (``from pkg import mod`` names pkg.mod)."""
    files = sorted((root / package).rglob("*.py"))
    modules = {module_name(root, f) for f in files}
    for path in files:
        importer = module_name(root, path)
        here = importer.split(".") if path.name == "__init__.py" else importer.split(".")[:-1]
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    base = ".".join(here[:len(here) - node.level + 1] + ([base] if base else []))
                targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base
                           for a in node.names]
            else:
                continue
            for target in dict.fromkeys(targets):  # once per statement, however many names
                if target == package or target.startswith(package + "."):
                    yield path, node.lineno, importer, _known(target, modules)


def _known(name: str, modules: set[str]) -> str:
    """The longest prefix of ``name`` that is a module (``import a.b.c`` of a name in a.b)."""
    while name not in modules and "." in name:
        name = name.rsplit(".", 1)[0]
    return name


def _package(module: str) -> str:
    """The package a module belongs to: mobot_cli.run.tf -> run; mobot_cli.errors -> errors."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def upward_imports(root: Path, package: str = "mobot_cli") -> list[str]:
    """Every import that breaks the layering, as 'file:line: what is wrong'."""
    problems = []
    for path, line, importer, imported in imports(root, package):
        src, dst = _package(importer), _package(imported)
        where = f"{path.relative_to(root)}:{line}: {importer} imports {imported}"
        if src == dst or dst in BOTTOM or src in TOP:
            continue
        if src in BOTTOM:
            problems.append(f"{where}, but {importer} is at the bottom and imports nothing above it")
        elif src not in LAYERS or dst not in LAYERS:
            unknown = src if src not in LAYERS else dst
            problems.append(f"{where}: package '{unknown}' has no layer (add it to LAYERS)")
        elif LAYERS[dst] > LAYERS[src]:
            problems.append(f"{where}: '{dst}' is a layer above '{src}'")
        elif LAYERS[dst] == LAYERS[src] and (src, dst) not in SAME_LAYER:
            allowed = ", ".join(f"{a} -> {b}" for a, b in sorted(SAME_LAYER))
            problems.append(f"{where}: '{src}' and '{dst}' share a layer (allowed: {allowed})")
    return problems


def import_cycles(root: Path, package: str = "mobot_cli") -> list[list[str]]:
    """Groups of modules that import each other, directly or around a loop (Tarjan's SCCs)."""
    graph: dict[str, set[str]] = {}
    for path in (root / package).rglob("*.py"):
        graph.setdefault(module_name(root, path), set())
    for _, _, importer, imported in imports(root, package):
        if imported != importer:
            graph[importer].add(imported)
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    cycles: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        for nxt in sorted(graph.get(node, ())):
            if nxt not in index:
                visit(nxt)
                low[node] = min(low[node], low[nxt])
            elif nxt in stack:
                low[node] = min(low[node], index[nxt])
        if low[node] == index[node]:
            group = []
            while True:
                member = stack.pop()
                group.append(member)
                if member == node:
                    break
            if len(group) > 1:
                cycles.append(sorted(group))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return cycles


def test_no_package_imports_a_layer_above_it():
    problems = upward_imports(REPO)
    assert not problems, "imports against the layering:\n" + "\n".join(problems)


def test_no_module_is_part_of_an_import_cycle():
    cycles = import_cycles(REPO)
    assert not cycles, "import cycles:\n" + "\n".join(" <-> ".join(c) for c in cycles)


def test_common_imports_nothing_of_mobot_but_errors():
    found = [f"{p.relative_to(REPO)}:{line}: {imported}" for p, line, importer, imported in imports(REPO)
             if _package(importer) == "common" and _package(imported) not in ("common", "errors")]
    assert not found


def test_every_package_has_a_layer():
    packages = {p.name for p in (REPO / "mobot_cli").iterdir() if (p / "__init__.py").is_file()}
    assert packages <= set(LAYERS), f"no layer for {sorted(packages - set(LAYERS))}"


def _tree(root: Path, files: dict[str, str]) -> Path:
    for name, text in {"mobot_cli/__init__.py": "", "mobot_cli/errors.py": "", **files}.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    return root


def test_the_checker_finds_upward_imports_at_any_depth(tmp_path):
    root = _tree(tmp_path, {
        "mobot_cli/sim/__init__.py": "",
        "mobot_cli/sim/world.py": "import math\nfrom mobot_cli.errors import X\n\n"
                                  "def f():\n    from mobot_cli.run import tf\n",
        "mobot_cli/sim/state.py": "from ..scenario.model import Spec\n",
        "mobot_cli/run/__init__.py": "",
        "mobot_cli/run/tf.py": "from mobot_cli.sim import world\nfrom mobot_cli.view import draw\n",
        "mobot_cli/view/__init__.py": "",
        "mobot_cli/view/draw.py": "import mobot_cli.run.tf\n",
        "mobot_cli/scenario/__init__.py": "",
        "mobot_cli/scenario/model.py": "",
        "mobot_cli/errors.py": "from mobot_cli.common import files\n",
        "mobot_cli/common/__init__.py": "",
        "mobot_cli/common/files.py": "",
    })
    problems = upward_imports(root)
    assert [p.split(": ")[0] for p in problems] == [
        "mobot_cli/errors.py:1", "mobot_cli/run/tf.py:2", "mobot_cli/sim/state.py:1",
        "mobot_cli/sim/world.py:5"]
    assert problems[3] == ("mobot_cli/sim/world.py:5: mobot_cli.sim.world imports mobot_cli.run.tf: "
                           "'run' is a layer above 'sim'")
    assert "mobot_cli.sim.state imports mobot_cli.scenario.model" in problems[2]  # relative import
    assert "'run' and 'view' share a layer" in problems[1]  # view -> run is fine, not run -> view


def test_the_checker_finds_cycles_through_function_level_imports(tmp_path):
    root = _tree(tmp_path, {
        "mobot_cli/assets/__init__.py": "",
        "mobot_cli/assets/load.py": "def load():\n    from mobot_cli.assets.build import build\n",
        "mobot_cli/assets/build.py": "from mobot_cli.assets import load\n",
        "mobot_cli/assets/types.py": "",
    })
    assert import_cycles(root) == [["mobot_cli.assets.build", "mobot_cli.assets.load"]]
    assert upward_imports(root) == []
