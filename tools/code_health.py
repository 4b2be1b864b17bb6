"""Code-health numbers for a source tree: what issue 34's "Done when" asks the lead to compare.

Why a script: the numbers (longest functions, classes with many methods, `noqa` / `type: ignore`
counts, `Any` in signatures, import cycles, duplicated code) were first gathered by hand with
one-off scans; written down once they can be taken again, the same way, before and after a change.

    python -m tools.code_health [--root DIR] [--json]

Definitions (all read from the source with `ast`/`tokenize`, nothing is imported except for the
import graph):
- files: every ``*.py`` below ``--root``, except hidden folders, ``.venv``, ``build``, ``__pycache__``.
- ``longest_functions``: the 15 longest ``def`` (end line - first line + 1, decorators left out) in
  the shipped packages (``--packages``, default dsr agents grammar scenes tools), as
  ``file:qualified.name:lines``.
- ``classes_over_20_methods``: classes (in the packages) with more than 20 ``def`` in their own body.
- ``noqa`` / ``type_ignore``: comments holding ``noqa`` / ``type: ignore``, in all files (tests
  included), with the split per top-level folder.
- ``any_in_signatures``: parameters and return annotations that mention ``Any`` (packages only);
  ``graph_any``: parameters named ``graph``, ``g`` or ``*_graph`` annotated ``Any`` itself, the DSR
  graph typed as ``Any`` (``dsr.protocols.GraphReader``/``GraphWriter`` replace it).
- ``import_cycles``: strongly connected groups of modules of the packages importing each other at
  run time (grimp's graph, ``if TYPE_CHECKING`` imports left out), each as a sorted list.
- ``duplicates``: the pair count of the workplace's ``duplicates`` command (six or more identical or
  same-shape lines), where that command exists; ``null`` with the reason otherwise.
"""
from __future__ import annotations

import argparse
import ast
import io
import json
import os
import re
import shutil
import subprocess
import sys
import tokenize
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

PACKAGES = ("dsr", "agents", "grammar", "scenes", "tools")
SKIP_DIRS = {".venv", "venv", "build", "dist", "__pycache__", "node_modules"}
LONGEST = 15
METHODS_LIMIT = 20
GRAPH_PARAM = re.compile(r"^(graph|g|\w+_graph)$")
NOQA = re.compile(r"#.*\bnoqa\b", re.IGNORECASE)
TYPE_IGNORE = re.compile(r"#.*\btype:\s*ignore\b")


@dataclass
class Health:
    """The numbers of one tree, in the order the report prints them."""

    files: int = 0
    duplicates: int | None = None
    duplicates_note: str = ""
    longest_functions: list[str] = field(default_factory=list)
    classes_over_20_methods: list[str] = field(default_factory=list)
    noqa: int = 0
    noqa_by_folder: dict[str, int] = field(default_factory=dict)
    type_ignore: int = 0
    type_ignore_by_folder: dict[str, int] = field(default_factory=dict)
    any_in_signatures: int = 0
    graph_any: int = 0
    import_cycles: list[list[str]] | None = None
    import_cycles_note: str = ""


def python_files(root: Path) -> list[Path]:
    """Every .py file below root, skipping hidden and build folders, sorted for stable output."""
    found: list[Path] = []
    for here, dirs, files in os.walk(root):
        dirs[:] = sorted(d for d in dirs if not d.startswith(".") and d not in SKIP_DIRS)
        found.extend(Path(here) / f for f in sorted(files) if f.endswith(".py"))
    return found


def _comments(source: str) -> list[str]:
    """The comment tokens of a file (a `noqa` inside a string is not a suppression)."""
    try:
        return [tok.string for tok in tokenize.generate_tokens(io.StringIO(source).readline)
                if tok.type == tokenize.COMMENT]
    except (tokenize.TokenError, SyntaxError):
        return [line[line.index("#"):] for line in source.splitlines() if "#" in line]


def _mentions_any(node: ast.expr | None) -> bool:
    if node is None:
        return False
    for sub in ast.walk(node):
        if isinstance(sub, ast.Name) and sub.id == "Any":
            return True
        if isinstance(sub, ast.Attribute) and sub.attr == "Any":
            return True
        if isinstance(sub, ast.Constant) and isinstance(sub.value, str) and re.search(r"\bAny\b", sub.value):
            return True
    return False


def _is_any(node: ast.expr | None) -> bool:
    """The annotation is ``Any`` itself (``Any``, ``typing.Any`` or the string ``"Any"``)."""
    return ((isinstance(node, ast.Name) and node.id == "Any") or (isinstance(node, ast.Attribute) and node.attr == "Any")
            or (isinstance(node, ast.Constant) and node.value == "Any"))


class _Scan(ast.NodeVisitor):
    """One pass over a module: function lengths, methods per class, `Any` in signatures."""

    def __init__(self, rel: str) -> None:
        self.rel = rel
        self.stack: list[str] = []
        self.functions: list[tuple[int, str]] = []
        self.big_classes: list[str] = []
        self.any_count = 0
        self.graph_any = 0

    def visit_ClassDef(self, node: ast.ClassDef) -> None:
        methods = sum(isinstance(b, ast.FunctionDef | ast.AsyncFunctionDef) for b in node.body)
        name = ".".join([*self.stack, node.name])
        if methods > METHODS_LIMIT:
            self.big_classes.append(f"{self.rel}:{name}:{methods}")
        self.stack.append(node.name)
        self.generic_visit(node)
        self.stack.pop()

    def _function(self, node: ast.FunctionDef | ast.AsyncFunctionDef) -> None:
        name = ".".join([*self.stack, node.name])
        length = (node.end_lineno or node.lineno) - node.lineno + 1
        self.functions.append((length, f"{self.rel}:{name}:{length}"))
        args = node.args
        params = [*args.posonlyargs, *args.args, *args.kwonlyargs,
                  *([args.vararg] if args.vararg else []), *([args.kwarg] if args.kwarg else [])]
        for p in params:
            if _mentions_any(p.annotation):
                self.any_count += 1
                if GRAPH_PARAM.match(p.arg) and _is_any(p.annotation):
                    self.graph_any += 1
        if _mentions_any(node.returns):
            self.any_count += 1
        self.stack.append(node.name)
        self.generic_visit(node)
        self.stack.pop()

    visit_FunctionDef = _function
    visit_AsyncFunctionDef = _function


def duplicate_pairs(root: Path) -> tuple[int | None, str]:
    """Pairs counted by the workplace's `duplicates` command, or None and why not."""
    exe = shutil.which("duplicates")
    if exe is None:
        return None, "the `duplicates` command is not on PATH"
    try:
        out = subprocess.run([exe, "--repo", str(root), "--most", "1", "--seconds", "120"],
                             capture_output=True, text=True, timeout=180, check=False).stdout
    except (OSError, subprocess.TimeoutExpired) as exc:
        return None, f"duplicates failed: {exc}"
    first = out.splitlines()[0] if out else ""
    if first.startswith("no duplicates"):
        return 0, first
    m = re.match(r"(\d+) pairs?\b", first)
    if not m:
        return None, f"unexpected duplicates output: {first!r}"
    note = "; ".join(line for line in out.splitlines() if line.startswith("incomplete:"))
    return int(m.group(1)), note or first


def import_cycles(root: Path, packages: Sequence[str]) -> tuple[list[list[str]] | None, str]:
    """Groups of modules that import each other at run time (grimp graph, networkx SCCs)."""
    try:
        import grimp
        import networkx as nx
    except ImportError as exc:
        return None, f"needs grimp and networkx: {exc}"
    present = [p for p in packages if (root / p / "__init__.py").exists()]
    if not present:
        return [], "no package found"
    sys.path.insert(0, str(root))
    try:
        graph = grimp.build_graph(*present, exclude_type_checking_imports=True, cache_dir=None)
    finally:
        sys.path.remove(str(root))
    g: nx.DiGraph = nx.DiGraph()
    for module in graph.modules:
        g.add_node(module)
        for target in graph.find_modules_directly_imported_by(module):
            g.add_edge(module, target)
    cycles = [sorted(c) for c in nx.strongly_connected_components(g) if len(c) > 1]
    cycles += [[m] for m in g.nodes if g.has_edge(m, m)]
    return sorted(cycles), ""


def measure(root: Path, packages: Sequence[str] = PACKAGES, *, with_duplicates: bool = True,
            with_cycles: bool = True) -> Health:
    """All the numbers of one tree."""
    root = root.resolve()
    health = Health()
    functions: list[tuple[int, str]] = []
    noqa: Counter[str] = Counter()
    ignores: Counter[str] = Counter()
    files = python_files(root)
    health.files = len(files)
    for path in files:
        rel = path.relative_to(root).as_posix()
        top = rel.split("/", 1)[0] if "/" in rel else "."
        source = path.read_text(encoding="utf-8", errors="replace")
        for comment in _comments(source):
            noqa[top] += bool(NOQA.search(comment))
            ignores[top] += bool(TYPE_IGNORE.search(comment))
        if top not in packages:
            continue
        try:
            tree = ast.parse(source, filename=rel)
        except SyntaxError:
            continue
        scan = _Scan(rel)
        scan.visit(tree)
        functions.extend(scan.functions)
        health.classes_over_20_methods.extend(scan.big_classes)
        health.any_in_signatures += scan.any_count
        health.graph_any += scan.graph_any
    functions.sort(key=lambda item: (-item[0], item[1]))
    health.longest_functions = [label for _, label in functions[:LONGEST]]
    health.classes_over_20_methods.sort(key=lambda s: (-int(s.rsplit(":", 1)[1]), s))
    health.noqa, health.noqa_by_folder = sum(noqa.values()), {k: v for k, v in sorted(noqa.items()) if v}
    health.type_ignore = sum(ignores.values())
    health.type_ignore_by_folder = {k: v for k, v in sorted(ignores.items()) if v}
    if with_duplicates:
        health.duplicates, health.duplicates_note = duplicate_pairs(root)
    else:
        health.duplicates_note = "not measured"
    if with_cycles:
        health.import_cycles, health.import_cycles_note = import_cycles(root, packages)
    else:
        health.import_cycles_note = "not measured"
    return health


def _text(h: Health) -> str:
    lines = [f"files: {h.files}",
             f"duplicate pairs: {h.duplicates if h.duplicates is not None else 'n/a'} ({h.duplicates_note})",
             f"noqa: {h.noqa} {h.noqa_by_folder}",
             f"type: ignore: {h.type_ignore} {h.type_ignore_by_folder}",
             f"Any in signatures: {h.any_in_signatures} (graph parameters: {h.graph_any})",
             f"longest {LONGEST} functions:", *(f"  {f}" for f in h.longest_functions),
             f"classes over {METHODS_LIMIT} methods:", *(f"  {c}" for c in h.classes_over_20_methods),
             "import cycles:" + ("" if h.import_cycles else f" none {h.import_cycles_note}".rstrip())]
    lines += [f"  {' <-> '.join(c)}" for c in h.import_cycles or []]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tools.code_health", description=__doc__.split("\n")[0])
    parser.add_argument("--root", type=Path, default=Path.cwd(), help="the tree to measure (default: here)")
    parser.add_argument("--packages", nargs="+", default=list(PACKAGES),
                        help="top-level packages whose code is measured (default: %(default)s)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--no-duplicates", action="store_true", help="skip the duplicate-code scan")
    args = parser.parse_args(argv)
    if not args.root.is_dir():
        print(f"code_health: {args.root} is not a folder; pass --root DIR", file=sys.stderr)
        return 2
    health = measure(args.root, args.packages, with_duplicates=not args.no_duplicates)
    print(json.dumps(health.__dict__, indent=1) if args.json else _text(health))
    return 0


if __name__ == "__main__":
    sys.exit(main())
