"""No import cycles between scalesynth's modules, counting imports inside functions and the two dynamic loaders
(cli._load_commands imports every scalesynth.commands module, the mechanism registry every mechanisms module), nor
between the scripts in benchmarks/; nothing the mechanisms are built on imports them back, and the evaluation
pipeline names no mechanism (each mechanism carries its own plans). Imports under ``if TYPE_CHECKING:`` are
annotations, never run, and do not count."""

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"
PKG = SRC / "scalesynth"
BENCH = ROOT / "benchmarks"


def _runtime_nodes(tree: ast.AST):
    """Every node of ``tree`` outside ``if TYPE_CHECKING:`` blocks (annotation-only imports)."""
    stack = [tree]
    while stack:
        node = stack.pop()
        yield node
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and ast.unparse(child.test) in ("TYPE_CHECKING", "typing.TYPE_CHECKING"):
                stack.extend(child.orelse)
                continue
            stack.append(child)


def _module_name(path: Path) -> str:
    rel = path.relative_to(SRC).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def import_graph() -> dict[str, set[str]]:
    """module -> the scalesynth modules it imports anywhere in its body (explicit and the known dynamic ones)."""
    modules = {_module_name(p): p for p in PKG.rglob("*.py")}
    graph: dict[str, set[str]] = {m: set() for m in modules}
    for name, path in modules.items():
        is_pkg = path.name == "__init__.py"
        for node in _runtime_nodes(ast.parse(path.read_text(encoding="utf-8"))):
            targets = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    anchor = name.split(".") if is_pkg else name.split(".")[:-1]
                    anchor = anchor[: len(anchor) - node.level + 1]
                    base = ".".join(anchor + ([base] if base else []))
                targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base for a in node.names]
            for t in targets:
                if t in modules and t != name:
                    graph[name].add(t)
    for loader, package in (("scalesynth.cli", "scalesynth.commands"),
                            ("scalesynth.mechanisms", "scalesynth.mechanisms")):
        graph[loader] |= {m for m in modules if m.startswith(package + ".")}
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_the_checker_finds_a_cycle():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def test_the_graph_sees_lazy_and_dynamic_imports():
    graph = import_graph()
    assert "scalesynth.kernels.grid" in graph["scalesynth.evaluation.report"]
    assert "scalesynth.evaluation.report" in graph["scalesynth.evaluate"]
    assert "scalesynth.commands.synthesis" in graph["scalesynth.cli"]
    assert "scalesynth.selection" in graph["scalesynth.commands.synthesis"]  # imported inside the command


def test_the_graph_skips_annotation_only_imports():
    graph = import_graph()
    # stiffness.report names Mechanism in annotations only (under TYPE_CHECKING)
    assert "scalesynth.mechanisms.base" not in graph["scalesynth.stiffness.report"]
    assert "scalesynth.stiffness.solve" in graph["scalesynth.stiffness.report"]


def test_no_import_cycles():
    assert cycles(import_graph()) == []


def _is_mechanisms(module: str) -> bool:
    return module == "scalesynth.mechanisms" or module.startswith("scalesynth.mechanisms.")


def _package(module: str) -> str:
    """The subpackage a module belongs to (scalesynth.stiffness.report -> scalesynth.stiffness), or the module."""
    parts = module.split(".")
    return ".".join(parts[:2])


def test_nothing_below_the_mechanisms_imports_them():
    """Every package (or top-level module) the mechanisms import is below them: none of its modules imports
    scalesynth.mechanisms or any module in it, not even inside a function."""
    graph = import_graph()
    below = {_package(t) for m, targets in graph.items() if _is_mechanisms(m) for t in targets
             if not _is_mechanisms(t)}
    assert {"scalesynth.stiffness", "scalesynth.kernels", "scalesynth.evaluation"} <= below
    upward = sorted(f"{m} -> {t}" for m, targets in graph.items() if _package(m) in below
                    for t in targets if _is_mechanisms(t))
    assert upward == []


def test_the_evaluation_pipeline_names_no_mechanism():
    """The evaluator's hand-tuned plans live with their mechanisms (Mechanism.node_plan, interval_plan,
    uniform_plan), so no registered mechanism's name appears in scalesynth.evaluation or scalesynth.evaluate."""
    from scalesynth.mechanisms import available

    names = available()
    assert "2pauu-ppap" in names
    hits = []
    for path in [PKG / "evaluate.py", *(PKG / "evaluation").glob("*.py")]:
        text = path.read_text(encoding="utf-8")
        hits += [f"{path.name}: {n}" for n in names if re.search(rf"(?<![\w-]){re.escape(n)}(?![\w-])", text)]
    assert hits == []


def benchmark_graph() -> dict[str, set[str]]:
    """benchmarks/ script -> the benchmarks/ scripts it imports anywhere in its body (they import each other as
    top-level modules, with benchmarks/ on sys.path)."""
    scripts = {p.stem: p for p in BENCH.glob("*.py")}
    graph: dict[str, set[str]] = {s: set() for s in scripts}
    for name, path in scripts.items():
        for node in _runtime_nodes(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                graph[name] |= {a.name for a in node.names if a.name in scripts}
            elif isinstance(node, ast.ImportFrom) and not node.level and node.module in scripts:
                graph[name].add(node.module)
    return graph


def test_no_import_cycles_among_the_benchmarks():
    graph = benchmark_graph()
    assert {"adaptive", "show_speed"} <= graph["bench"]  # the checker sees the scripts' imports
    assert cycles(graph) == []
