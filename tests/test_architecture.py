"""The house rules on the shape of the code (DEVELOPERS.md), checked on the source text.

* Data flows one way: ``analytic`` <- ``sim_models`` <- ``reports``.  No package imports
  one above it, and no module imports itself back through others: an import cycle is
  a failure whether the imports sit at module level or inside functions (a function-level
  import hides a cycle from the interpreter, not from the design).
* Inside ``sim_models/engines/`` each engine is one folder, and no engine's folder imports
  another's (:data:`ENGINE_BASES` names the one engine built on another's model).
* Only the command line reads command-line arguments: ``argparse`` is imported by the
  command-line modules alone (:data:`COMMAND_LINE`), and no library module imports one
  of them.

The modules are read with :mod:`ast`, never imported, so a test here fails by naming the
import (file and line), not by an import error.
"""

from __future__ import annotations

import ast
import functools
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: The project's packages, lowest first: each may import only those before it.
LAYERS = ("analytic", "sim_models", "reports")
#: The top-level pytest entry point (above ``reports``: it may import all three).
TOP_MODULES = ("xval_pytest_plugin",)

#: The command line: the modules that build ``xval``'s parser and turn its arguments into
#: calls of the library (:func:`command_line_modules`):
#:
#: * ``reports.cli.xval`` (the parser, the ``COMMANDS`` table, its own commands ``cases``,
#:   ``solve``, ``sweep``), ``reports.cli.options`` (option types, ``OneLineParser``),
#:   ``reports.cli.paths`` (what a command may write);
#: * every module named in ``reports.cli.xval.COMMANDS`` (each adds its commands with
#:   ``register(sub)``);
#: * the command modules a command hands its work to, named ``*_cmd`` or ``*_cli``
#:   (``baseline_cli``, ``report_cmd``, ``plot_cmd`` ..., and ``studies_cmd``, the
#:   maintainer's ``python -m reports.cli.studies``);
#: * ``xval_pytest_plugin``, pytest's entry point (it adds pytest options).
#:
#: Everything else is library code: it takes typed values, never an ``argparse``
#: parser or namespace, and imports none of the modules above.
COMMAND_LINE_CORE = frozenset({"reports.cli.xval", "reports.cli.options", "reports.cli.paths",
                               "xval_pytest_plugin"})
#: Modules that read ``sys.argv`` without being the command line: the background kernel
#: compiler's worker process, whose arguments are written by
#: :func:`analytic.kernels.background.start`, not typed by a user.  (The maintainer
#: scripts in ``scripts/``, ``readme_figures.py`` among them, are not in the installed
#: packages, so not in this check.)
ARGV_READERS = frozenset({"analytic.kernels.background"})

#: The engine folders of ``sim_models/engines/`` that may import another engine's folder:
#: MuJoCo Warp runs MuJoCo's own model (built by ``builders/mjcf.py``) on another stepper,
#: and its sessions subclass MuJoCo's, so the model's indexing, loads and readout are
#: written once.  Any other engine-to-engine import is a failure.
ENGINE_BASES: dict[str, frozenset[str]] = {"mujoco_warp": frozenset({"mujoco"})}


@dataclass(frozen=True)
class Import:
    """One import statement's target as written in ``source`` (a module name, resolved
    from a relative import), at ``line``; ``nested`` if inside a function or class;
    ``by_name`` if it is a string that ``source`` hands to ``importlib.import_module``
    (the engine registry, the command table)."""

    source: str
    target: str
    line: int
    nested: bool
    by_name: bool = False


def module_name(path: Path, root: Path | None = None) -> str:
    """``reports/cli/xval.py`` -> ``reports.cli.xval``; a package's ``__init__`` -> the package."""
    rel = path.relative_to(root or ROOT).with_suffix("")
    parts = rel.parts[:-1] if rel.name == "__init__" else rel.parts
    return ".".join(parts)


def project_files() -> dict[str, Path]:
    """Module name -> file for every module of the three packages and the entry point."""
    out = {}
    for pkg in LAYERS:
        for path in sorted((ROOT / pkg).rglob("*.py")):
            out[module_name(path)] = path
    for name in TOP_MODULES:
        out[name] = ROOT / f"{name}.py"
    return out


def _where(path: Path) -> str:
    return str(path.relative_to(ROOT)) if path.is_relative_to(ROOT) else str(path)


def _package_of(name: str, path: Path) -> str:
    """The package a relative import in module ``name`` is relative to."""
    return name if path.name == "__init__.py" else name.rpartition(".")[0]


def imports_of(name: str, path: Path) -> list[Import]:
    """Every import in one module, module-level and nested, relative ones resolved.
    ``from P import X`` yields ``P.X`` (X may be a submodule) and ``P``."""
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    nested_lines = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef | ast.Lambda):
            for sub in ast.walk(node):
                if sub is not node:
                    nested_lines.add(id(sub))
    out = []
    for node in ast.walk(tree):
        nested = id(node) in nested_lines
        if isinstance(node, ast.Import):
            out += [Import(name, a.name, node.lineno, nested) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = _package_of(name, path).split(".")
                base = base[:len(base) - (node.level - 1)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            out.append(Import(name, mod, node.lineno, nested))
            out += [Import(name, f"{mod}.{a.name}", node.lineno, nested) for a in node.names]
    return out


def imports_by_name(name: str, path: Path, modules) -> list[Import]:
    """A module that calls ``importlib.import_module``, or hands its names to
    :func:`reports.lazy_exports.lazy_getattr` (the front doors), imports, when asked, the
    project modules it names in string constants (``sim_models.engines.registry.BUILTIN``,
    ``reports.cli.xval.COMMANDS``, a front door's ``_EXPORTS``): one edge each, its own
    name left out."""
    text = path.read_text(encoding="utf-8")
    if "import_module" not in text and "lazy_getattr(" not in text:
        return []
    return [Import(name, node.value, node.lineno, True, by_name=True)
            for node in ast.walk(ast.parse(text, str(path)))
            if isinstance(node, ast.Constant) and isinstance(node.value, str)
            and node.value in modules and node.value != name]


def project_imports() -> tuple[dict[str, Path], list[Import]]:
    """The project's modules and the imports between them (:func:`edges_of`), read once
    per ``ROOT``."""
    return _project_imports(ROOT)


@functools.cache
def _project_imports(root: Path) -> tuple[dict[str, Path], list[Import]]:
    files = project_files()
    return files, edges_of(files)


def edges_of(files: dict[str, Path]) -> list[Import]:
    """For each import of one of ``files``' modules by another, the edge to the module it
    loads (``from P import X`` resolves to ``P.X`` when that is a module, else ``P``)."""
    edges = []
    for name, path in files.items():
        for imp in imports_of(name, path) + imports_by_name(name, path, files):
            if imp.target in files:
                edges.append(imp)
    # ``from P import X`` added both P.X and P: keep P only when X is not a module
    # (P's __init__ still runs, but a package's __init__ importing its own submodules
    # is a front door, not a cycle through the submodule).
    on_line: dict[tuple[str, int], set[str]] = {}
    for e in edges:
        on_line.setdefault((e.source, e.line), set()).add(e.target)
    kept, seen = [], set()
    for imp in edges:
        targets = on_line[(imp.source, imp.line)]
        if any(t.startswith(imp.target + ".") for t in targets):
            continue  # the parent of a submodule imported on the same line
        if (imp.source, imp.target, imp.line) not in seen:
            seen.add((imp.source, imp.target, imp.line))
            kept.append(imp)
    return kept


def strongly_connected(nodes, edges: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's strongly connected components of a directed graph (iterative)."""
    index, low, on_stack, stack, comps = {}, {}, set(), [], []
    counter = 0
    for root in nodes:
        if root in index:
            continue
        work = [(root, iter(sorted(edges.get(root, ()))))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            v, it = work[-1]
            for w in it:
                if w not in index:
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(edges.get(w, ())))))
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
                    comps.append(sorted(comp))
    return comps


def import_cycles(files, imports: list[Import]) -> list[str]:
    """One line per cycle: its modules and the imports that close it (file:line)."""
    graph: dict[str, set[str]] = {}
    for imp in imports:
        graph.setdefault(imp.source, set()).add(imp.target)
    lines = []
    for comp in strongly_connected(sorted(files), graph):
        if len(comp) == 1 and comp[0] not in graph.get(comp[0], ()):
            continue
        members = set(comp)
        where = sorted(f"{i.source} -> {i.target} ({_where(files[i.source])}:"
                       f"{i.line}{_how(i)})"
                       for i in imports if i.source in members and i.target in members)
        lines.append(f"cycle of {len(comp)}: {', '.join(comp)}\n    " + "\n    ".join(where))
    return sorted(lines)


def _how(imp: Import) -> str:
    return ", by name" if imp.by_name else ", in a function" if imp.nested else ""


def _layer(module: str) -> int:
    top = module.split(".")[0]
    return LAYERS.index(top) if top in LAYERS else len(LAYERS)


def upward_imports(files, imports: list[Import]) -> list[str]:
    return [f"{_where(files[i.source])}:{i.line}: {i.source} imports {i.target}, "
            "a package above it" for i in imports if _layer(i.target) > _layer(i.source)]


def engine_folders(root: Path | None = None) -> frozenset[str]:
    """The engines' folders in ``sim_models/engines/`` (each a package)."""
    base = (root or ROOT) / "sim_models" / "engines"
    return frozenset(p.parent.name for p in base.glob("*/__init__.py"))


def _engine_of(module: str, engines) -> str | None:
    """The engine whose folder holds ``module`` (``sim_models.engines.NAME...``), or None."""
    parts = module.split(".")
    if parts[:2] == ["sim_models", "engines"] and len(parts) > 2 and parts[2] in engines:
        return parts[2]
    return None


def cross_engine_imports(files, imports: list[Import], engines,
                         bases=ENGINE_BASES) -> list[str]:
    """One line per import from one engine's folder into another's (not its declared
    base, :data:`ENGINE_BASES`)."""
    out = []
    for i in imports:
        a, b = _engine_of(i.source, engines), _engine_of(i.target, engines)
        if a and b and a != b and b not in bases.get(a, ()):
            out.append(f"{_where(files[i.source])}:{i.line}: {i.source} imports {i.target} "
                       f"(engine {a!r} from engine {b!r}'s folder{_how(i)})")
    return out


def command_line_modules() -> frozenset[str]:
    """:data:`COMMAND_LINE_CORE`, every module of ``reports/cli/`` (and any ``reports``
    module named ``*_cmd``/``*_cli``), and
    every module named in ``reports.cli.xval.COMMANDS`` (read from the source: the first
    string of each of the table's values)."""
    named = {module_name(p) for p in (ROOT / "reports" / "cli").rglob("*.py")}
    named |= {f"reports.{p.stem}" for p in (ROOT / "reports").glob("*.py")
              if p.stem.endswith(("_cmd", "_cli"))}
    tree = ast.parse((ROOT / "reports" / "cli" / "xval.py").read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, ast.Assign | ast.AnnAssign):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            if any(isinstance(t, ast.Name) and t.id == "COMMANDS" for t in targets):
                table = ast.literal_eval(node.value)
                return COMMAND_LINE_CORE | named | {module for module, _ in table.values()}
    raise AssertionError("reports/cli/xval.py has no COMMANDS table")


# ============================================================================ the checker
def test_the_checker_finds_what_it_should(tmp_path):
    """The graph code itself: a two-module cycle through a function-level import, a
    self-import, relative imports two levels up, a package front door importing its own
    submodule (no cycle), and a clean chain."""
    assert strongly_connected("abc", {"a": {"b"}, "b": {"a"}, "c": {"a"}}) == [
        ["a", "b"], ["c"]]
    pkg = tmp_path / "reports"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("from .e import E\n")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "a.py").write_text("from . import b\n")
    (pkg / "b.py").write_text("def f():\n    from .a import thing\n")
    (pkg / "c.py").write_text("def g():\n    import reports.c\n")
    (pkg / "sub" / "d.py").write_text("from ..a import x\nfrom .. import b\n")
    (pkg / "e.py").write_text("import numpy\nfrom .sub import d\n")
    (pkg / "f.py").write_text("import importlib\nTABLE = {'g': 'reports.g', 'f': 'reports.f'}\n"
                              "def load(k):\n    return importlib.import_module(TABLE[k])\n")
    (pkg / "g.py").write_text("from .f import TABLE\n")
    files = {module_name(p, tmp_path): p for p in sorted(pkg.rglob("*.py"))}
    edges = edges_of(files)
    pairs = {(i.source, i.target) for i in edges}
    assert {("reports.sub.d", "reports.a"), ("reports.sub.d", "reports.b"),
            ("reports", "reports.e"), ("reports.e", "reports.sub.d"),
            ("reports.f", "reports.g")} <= pairs
    assert ("reports.sub.d", "reports") not in pairs  # the parent of a submodule import
    cycles = import_cycles(files, edges)
    assert len(cycles) == 3, cycles
    assert "cycle of 1: reports.c" in cycles[0]
    assert "reports.a, reports.b" in cycles[1] and "in a function" in cycles[1]
    assert "reports.f, reports.g" in cycles[2] and "by name" in cycles[2]
    assert upward_imports(files, edges) == []
    (pkg / "e.py").write_text("import numpy\nfrom sim_models import x\n")
    files["sim_models"] = tmp_path / "sim_models" / "__init__.py"
    late = [i for i in imports_of("reports.e", pkg / "e.py") if i.target in files]
    assert upward_imports(files, late) == [] and _layer("sim_models") < _layer("reports")
    bad = [Import("sim_models", "reports.e", 3, True)]
    assert "a package above it" in upward_imports(files, bad)[0]


# ============================================================================ the rules
@pytest.mark.parametrize("package", LAYERS)
def test_no_import_cycles(package):
    """No cycle among ``package``'s modules, counting imports inside functions and the
    modules a table hands to ``importlib``.  (A cycle across packages needs an upward
    import: :func:`test_no_package_imports_one_above_it`.)"""
    files, imports = project_imports()
    cycles = [c for c in import_cycles(files, imports)
              if c.split(": ", 1)[1].startswith(package + ".")
              or c.split(": ", 1)[1].startswith(package + ",")]
    assert not cycles, "import cycles:\n" + "\n".join(cycles)


def test_the_whole_graph_has_no_cycle():
    """The same over all three packages and the pytest entry point at once."""
    files, imports = project_imports()
    cycles = import_cycles(files, imports)
    assert not cycles, "import cycles:\n" + "\n".join(cycles)


def test_no_package_imports_one_above_it():
    """analytic <- sim_models <- reports: ``analytic`` imports neither of the others,
    ``sim_models`` not ``reports`` (function-level imports counted)."""
    files, imports = project_imports()
    bad = upward_imports(files, imports)
    assert not bad, "\n".join(bad)


def test_analytic_imports_nothing_of_sim_models_or_reports():
    """The product stands alone: no ``analytic`` module imports ``sim_models`` or
    ``reports``, at module level, inside a function or by name."""
    files, imports = project_imports()
    bad = [f"{_where(files[i.source])}:{i.line}: {i.source} imports {i.target}{_how(i)}"
           for i in imports if i.source.split(".")[0] == "analytic"
           and i.target.split(".")[0] in ("sim_models", "reports")]
    assert not bad, "\n".join(bad)


def test_no_engine_folder_imports_another():
    """Each engine's folder (``sim_models/engines/NAME/``) imports the protocol, the
    builders and the runs' records, never another engine's folder (function-level and
    by-name imports counted), but for :data:`ENGINE_BASES`."""
    engines = engine_folders()
    assert {"mujoco", "pybullet", "exudyn", "pinocchio", "mujoco_warp"} <= engines
    files, imports = project_imports()
    bad = cross_engine_imports(files, imports, engines)
    assert not bad, "imports between engine folders:\n" + "\n".join(bad)
    # the rule's reach: a released PyBullet session importing MuJoCo's would be named,
    # and MuJoCo Warp's import of MuJoCo is there and allowed only by ENGINE_BASES
    fake = [Import("sim_models.engines.pybullet.free", "sim_models.engines.mujoco.driven",
                   7, True)]
    assert "engine 'pybullet' from engine 'mujoco'" in cross_engine_imports(
        files, fake, engines)[0]
    warp = [i for i in imports if _engine_of(i.source, engines) == "mujoco_warp"
            and _engine_of(i.target, engines) == "mujoco"]
    assert warp and cross_engine_imports(files, warp, engines, bases={})


def test_no_cycle_with_the_tests():
    """No import cycle in the packages and ``tests/`` together (the tests import the
    packages and each other's helpers; function-level imports counted)."""
    files = dict(project_files())
    files.update({module_name(p): p for p in sorted((ROOT / "tests").rglob("*.py"))})
    cycles = import_cycles(files, edges_of(files))
    assert not cycles, "import cycles:\n" + "\n".join(cycles)


def _reads_argv(path: Path) -> list[int]:
    """Lines where a module reads ``sys.argv``."""
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    return [n.lineno for n in ast.walk(tree) if isinstance(n, ast.Attribute)
            and n.attr == "argv" and isinstance(n.value, ast.Name) and n.value.id == "sys"]


def test_only_the_command_line_reads_arguments():
    """``argparse`` is imported only by the command-line modules, and ``sys.argv`` read
    only there (and by :data:`ARGV_READERS`); a library module takes typed values."""
    cli = command_line_modules()
    files = project_files()
    assert cli <= set(files), f"unknown command modules: {sorted(cli - set(files))}"
    assert "reports.cli.compare" in cli and "reports.cli.baseline" in cli  # the rule's reach
    bad = []
    for name, path in files.items():
        if name in cli:
            continue
        bad += [f"{_where(path)}:{i.line}: {name} imports argparse"
                for i in imports_of(name, path)
                if i.target == "argparse" or i.target.startswith("argparse.")]
        if name not in ARGV_READERS:
            bad += [f"{_where(path)}:{line}: {name} reads sys.argv"
                    for line in _reads_argv(path)]
    assert not bad, "command-line arguments read outside the command line:\n" + "\n".join(bad)


def test_library_modules_do_not_import_the_command_line():
    """No library module imports a command-line module (the command line calls the
    library, never the other way round); the package front doors are library code."""
    cli = command_line_modules()
    files, imports = project_imports()
    bad = [f"{_where(files[i.source])}:{i.line}: {i.source} imports {i.target}"
           for i in imports if i.source not in cli and i.target in cli]
    assert not bad, "library modules importing the command line:\n" + "\n".join(bad)


def test_the_command_line_is_reports_cli():
    """Every command's module lives in ``reports/cli/`` and every module there is the
    command line: outside it (and the pytest entry point) nothing may import argparse or
    a ``reports.cli`` module (:func:`test_only_the_command_line_reads_arguments`,
    :func:`test_library_modules_do_not_import_the_command_line`)."""
    cli = command_line_modules()
    outside = sorted(m for m in cli if not (m == "reports.cli" or m.startswith("reports.cli."))
                     and m not in TOP_MODULES)
    assert not outside, f"command-line modules outside reports/cli/: {outside}"


def test_maintainer_scripts_are_not_installed():
    """``scripts/`` (``readme_figures.py``: it edits the checkout's README) is not an
    installed package: not matched by ``pyproject.toml``'s package search, not a
    ``py-modules`` entry, and no ``__init__.py`` that would make it one."""
    import fnmatch
    import tomllib
    cfg = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    st = cfg["tool"]["setuptools"]
    include = st["packages"]["find"]["include"]
    assert (ROOT / "scripts" / "readme_figures.py").is_file()
    assert not any(fnmatch.fnmatch("scripts", pat) for pat in include), include
    assert not any(m.startswith("scripts") for m in st.get("py-modules", []))
    assert not (ROOT / "scripts" / "__init__.py").exists()
