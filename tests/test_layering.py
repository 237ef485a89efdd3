"""The package's layering, read from the source (no imports run).

- no import cycle among shipgym's modules (every ``import`` statement counts, those inside
  functions too; only ``if TYPE_CHECKING:`` blocks, which never run, are left out);
- the command-line modules ``shipgym.cli`` and ``shipgym.rl.cli`` are leaves: no library
  module imports them (``shipgym.cli`` mounts ``shipgym.rl.cli``'s subcommands, nothing else);
- the pure-NumPy layers (the vessel model in ``shipgym.dynamics``, and what holds today of the
  disturbances, guidance, observers and controllers) never reach MuJoCo or Gymnasium, directly
  or through another shipgym module.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "shipgym"
CLI_MODULES = ("shipgym.cli", "shipgym.rl.cli")
SIMULATOR_PACKAGES = ("mujoco", "gymnasium", "gym")


def _module_name(path: Path, root: Path) -> str:
    parts = list(path.relative_to(root.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _imports(tree: ast.AST) -> list[ast.Import | ast.ImportFrom]:
    """Every import statement that can run (``if TYPE_CHECKING:`` bodies left out)."""
    out: list[ast.Import | ast.ImportFrom] = []
    todo: list[ast.AST] = [tree]
    while todo:
        node = todo.pop()
        if isinstance(node, ast.Import | ast.ImportFrom):
            out.append(node)
            continue
        if isinstance(node, ast.If) and _is_type_checking(node.test):
            todo.extend(node.orelse)
            continue
        todo.extend(ast.iter_child_nodes(node))
    return out


def _targets(module: str, is_package: bool, node: ast.Import | ast.ImportFrom) -> list[str]:
    """Absolute names an import statement may refer to (the module, and module.name)."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names]
    base = node.module or ""
    if node.level:
        parts = module.split(".") if is_package else module.split(".")[:-1]
        parts = parts[: len(parts) - (node.level - 1)]
        base = ".".join([*parts, *([node.module] if node.module else [])])
    return [base, *(f"{base}.{a.name}" for a in node.names)]


def import_graph(root: Path = ROOT) -> tuple[dict[str, set[str]], dict[str, set[str]]]:
    """``(internal, external)``: for each shipgym module, the shipgym modules it imports and
    the top-level names of the other packages it imports."""
    files = {_module_name(p, root): p for p in sorted(root.rglob("*.py"))}
    internal: dict[str, set[str]] = {}
    external: dict[str, set[str]] = {}
    for mod, path in files.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        is_pkg = path.name == "__init__.py"
        deps: set[str] = set()
        ext: set[str] = set()
        for node in _imports(tree):
            for name in _targets(mod, is_pkg, node):
                if name in files and name != mod:
                    deps.add(name)
                elif name and not name.startswith("shipgym"):
                    ext.add(name.split(".")[0])
        internal[mod] = deps
        external[mod] = ext
    return internal, external


def strongly_connected(graph: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's strongly connected components (iterative), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out: list[list[str]] = []
    counter = 0
    for start in graph:
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = counter
        counter += 1
        stack.append(start)
        on_stack.add(start)
        while work:
            v, it = work[-1]
            for w in it:
                if w not in index:
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(graph.get(w, ())))))
                    break
                if w in on_stack:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    comp = []
                    while True:
                        w = stack.pop()
                        on_stack.discard(w)
                        comp.append(w)
                        if w == v:
                            break
                    out.append(sorted(comp))
    return out


def _reach(graph: dict[str, set[str]], start: str) -> set[str]:
    seen = {start}
    todo = [start]
    while todo:
        for w in graph[todo.pop()]:
            if w not in seen:
                seen.add(w)
                todo.append(w)
    return seen


GRAPH, EXTERNAL = import_graph()


def test_the_graph_sees_the_package():
    """The checks below read real edges (a parser that found none would pass them all)."""
    assert len(GRAPH) > 40
    assert "shipgym.runner" in GRAPH["shipgym.cli"]
    assert "shipgym.rl.cli" in GRAPH["shipgym.cli"]  # a function-level import
    assert "shipgym.bench" in GRAPH["shipgym.rl.bench"]
    assert "shipgym.rl.evaluation" in GRAPH["shipgym.rl.bench"]  # a relative import
    assert "mujoco" in EXTERNAL["shipgym.sim._mujoco"]
    assert "shipgym.sim._mujoco" in GRAPH["shipgym.sim.step"]


def test_the_cycle_finder_finds_cycles():
    g = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}, "e": {"e"}}
    comps = strongly_connected(g)
    assert ["a", "b", "c"] in comps
    assert ["d"] in comps


def test_relative_and_type_checking_imports(tmp_path):
    pkg = tmp_path / "shipgym"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "top.py").write_text("def f():\n    from shipgym.sub import a\n")
    (pkg / "sub" / "__init__.py").write_text("from . import a\n")
    (pkg / "sub" / "a.py").write_text(
        "from typing import TYPE_CHECKING\nfrom ..top import f\nimport mujoco.viewer\n"
        "if TYPE_CHECKING:\n    from shipgym.sub import b\n"
    )
    (pkg / "sub" / "b.py").write_text("from .a import x\n")
    g, ext = import_graph(pkg)
    assert g["shipgym.top"] == {"shipgym.sub", "shipgym.sub.a"}
    assert g["shipgym.sub"] == {"shipgym.sub.a"}
    assert g["shipgym.sub.a"] == {"shipgym.top"}  # b only under TYPE_CHECKING
    assert g["shipgym.sub.b"] == {"shipgym.sub.a"}
    assert ext["shipgym.sub.a"] == {"typing", "mujoco"}
    assert ["shipgym.sub", "shipgym.sub.a", "shipgym.top"] in strongly_connected(g)


def test_no_import_cycles():
    cycles = [c for c in strongly_connected(GRAPH) if len(c) > 1]
    cycles += [[m] for m, deps in GRAPH.items() if m in deps]
    assert cycles == [], f"import cycles in shipgym: {cycles}"


def test_command_line_modules_are_leaves():
    users = {
        (mod, cli)
        for mod, deps in GRAPH.items()
        for cli in CLI_MODULES
        if cli in deps and not (mod == "shipgym.cli" and cli == "shipgym.rl.cli")
    }
    assert users == set(), f"library modules import the command line: {sorted(users)}"


@pytest.mark.parametrize(
    "package",
    [
        "shipgym.dynamics",
        "shipgym.disturbances",
        "shipgym.guidance",
        "shipgym.observers.base",
        "shipgym.observers.kalman",
        "shipgym.observers.ekf",
        "shipgym.observers.notch",
        "shipgym.observers.design",
        "shipgym.observers.sensors",
        "shipgym.observers.batch",
        "shipgym.controllers.allocation",
        "shipgym.controllers.pid",
        "shipgym.controllers.batch",
        "shipgym.metrics",
        "shipgym.records",
        "shipgym.observers.wavefilter",
        "shipgym.controllers.design",
        "shipgym.controllers.grimble",
        "shipgym.dp.metrics",
        "shipgym.dp.seed",
        "shipgym.dynamics.vanderklugt",
        "shipgym.observers.sway",
        "shipgym.controllers.rollcontrol",
        "shipgym.controllers.rollpilot",
        "shipgym.dynamics.linearise",
        "shipgym.dynamics.blanke4",
        "shipgym.disturbances.rollwaves",
        "shipgym.observers.dgps",
        "shipgym.dynamics.mmg",
        "shipgym.trials",
        "shipgym.controllers.coursepilot",
    ],
)
def test_pure_layers_never_reach_the_simulator(package):
    """A module of ``package`` and everything it imports in shipgym stay off MuJoCo/Gymnasium.

    (``shipgym.controllers.lq`` is not in the list: its ``register_lq`` registers it with the
    named controllers the envs run.)
    """
    mods = [m for m in GRAPH if m == package or m.startswith(package + ".")]
    assert mods, f"no module {package}"
    for mod in mods:
        for m in _reach(GRAPH, mod):
            bad = EXTERNAL[m] & set(SIMULATOR_PACKAGES)
            assert not bad, f"{mod} reaches {sorted(bad)} through {m}"


DP_USERS = ("shipgym.cli", "shipgym.bench")


def test_dp_is_a_high_layer():
    """``shipgym.dp`` may use the pure layers; only the command line and the bench import it."""
    assert "shipgym.dp.metrics" in GRAPH["shipgym.dp"]  # the check reads real edges
    users = {
        mod
        for mod, deps in GRAPH.items()
        if not (mod == "shipgym.dp" or mod.startswith("shipgym.dp."))
        and any(d == "shipgym.dp" or d.startswith("shipgym.dp.") for d in deps)
    }
    assert users <= set(DP_USERS), f"modules importing shipgym.dp: {sorted(users - set(DP_USERS))}"


def test_the_cli_still_exports_what_it_documents():
    """The helpers moved down are the same objects under their old names in shipgym.cli."""
    import shipgym._argtypes
    import shipgym.bench
    import shipgym.catalogue
    import shipgym.cli
    import shipgym.runner

    cli = shipgym.cli
    assert cli.parse_wind is shipgym._argtypes.parse_wind
    assert cli.run_episode is shipgym.runner.run_episode
    assert cli.ENV_DEFAULT is shipgym.runner.ENV_DEFAULT
    assert cli.check_controller is shipgym.catalogue.check_controller
    assert cli.catalogue is shipgym.catalogue.catalogue
    assert cli.write_bench_outputs is shipgym.bench.write_bench_outputs
    assert set(cli.__all__) <= set(vars(cli))


def test_rrs_is_a_high_layer():
    """``shipgym.rrs`` (the roll bench) may use every layer below; only the command line and
    the viz import it."""
    assert "shipgym.rrs.bench" in GRAPH
    users = {
        mod
        for mod, deps in GRAPH.items()
        if not (mod == "shipgym.rrs" or mod.startswith("shipgym.rrs."))
        and any(d == "shipgym.rrs" or d.startswith("shipgym.rrs.") for d in deps)
    }
    assert users <= {"shipgym.cli"}, f"modules importing shipgym.rrs: {sorted(users)}"
