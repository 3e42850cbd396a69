"""The shape of the code, as DEVELOPERS.md and issue 19 measure it (read with :mod:`ast`).

* the tree of ``reports/`` and of ``sim_models/``: each folder and module with its line
  count and the first line of its docstring;
* per package, the longest module (house target: at most 500 lines) and every module
  over it;
* per package, the longest class (a class's lines run from its ``class`` line to its
  last statement, docstring and methods included; target at most 300 lines) and every
  class over it;
* every function over 80 lines in ``analytic``, ``sim_models``, ``reports`` and the
  pytest entry point, and in ``tests``, ``benchmarks`` and ``scripts`` (a function's
  lines run from its ``def`` to its last statement, docstring and nested functions
  included);
* the share of ``import`` statements in ``reports/`` that sit inside a function or
  class body (target under 5%).  ``xval``'s lazy command loading is a table of module
  names handed to ``importlib``, not an import statement, so it is not counted either way.

    python benchmarks/code_shape.py [--root DIR] [--tree]
"""

from __future__ import annotations

import argparse
import ast
from pathlib import Path

PACKAGES = ("analytic", "sim_models", "reports")
TOP_MODULES = ("xval_pytest_plugin.py",)
MAX_MODULE = 500
MAX_CLASS = 300
MAX_FUNCTION = 80


def _files(root: Path, packages=PACKAGES) -> list[Path]:
    out = [p for pkg in packages for p in sorted((root / pkg).rglob("*.py"))]
    return out + [root / m for m in TOP_MODULES if (root / m).is_file() and packages
                  == PACKAGES]


def _lines(path: Path) -> int:
    return len(path.read_text(encoding="utf-8").splitlines())


#: Code outside the installed packages that the function rule covers too.
OTHER_CODE = ("tests", "benchmarks", "scripts")


def long_functions(root: Path, limit: int = MAX_FUNCTION,
                   packages=PACKAGES) -> list[tuple[int, str]]:
    """(lines, 'file:line name') of every function longer than ``limit`` lines."""
    out = []
    for path in _files(root, packages):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                n = node.end_lineno - node.lineno + 1
                if n > limit:
                    out.append((n, f"{path.relative_to(root)}:{node.lineno} {node.name}"))
    return sorted(out, reverse=True)


def classes(root: Path, package: str) -> list[tuple[int, str]]:
    """(lines, 'file:line name') of every class in ``package``, longest first."""
    out = []
    for path in _files(root, (package,)):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ClassDef):
                n = node.end_lineno - node.lineno + 1
                out.append((n, f"{path.relative_to(root)}:{node.lineno} {node.name}"))
    return sorted(out, reverse=True)


def package_lines(root: Path, package: str) -> list[str]:
    """Per package: its modules and lines, the longest module and those over
    :data:`MAX_MODULE`, the longest class and those over :data:`MAX_CLASS`."""
    mods = sorted(((_lines(f), str(f.relative_to(root))) for f in _files(root, (package,))),
                  reverse=True)
    over = [m for m in mods if m[0] > MAX_MODULE]
    out = [f"{package}/: {len(mods)} modules, {sum(n for n, _ in mods)} lines; longest "
           f"{mods[0][1]} ({mods[0][0]} lines); {len(over)} over {MAX_MODULE}"
           + (": " + ", ".join(f"{f} ({n})" for n, f in over) if over else "")]
    cls = classes(root, package)
    if cls:
        big = [c for c in cls if c[0] > MAX_CLASS]
        out.append(f"{package}/ classes: {len(cls)}; longest {cls[0][1]} ({cls[0][0]} lines); "
                   f"{len(big)} over {MAX_CLASS}"
                   + (": " + ", ".join(f"{w} ({n})" for n, w in big) if big else ""))
    return out


def import_share(root: Path, package: str = "reports") -> tuple[int, int, dict[str, int]]:
    """(imports inside functions, all imports, inside-function count per module) in
    ``package``; an ``import`` statement counts once however many names it binds."""
    nested_total = total = 0
    per_module: dict[str, int] = {}
    for path in _files(root, (package,)):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        inside = set()
        for node in ast.walk(tree):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
                inside |= {id(s) for s in ast.walk(node) if s is not node}
        for node in ast.walk(tree):
            if isinstance(node, ast.Import | ast.ImportFrom):
                total += 1
                if id(node) in inside:
                    nested_total += 1
                    key = str(path.relative_to(root))
                    per_module[key] = per_module.get(key, 0) + 1
    return nested_total, total, per_module


def _first_line(path: Path) -> str:
    doc = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8"))) or ""
    return " ".join(doc.split("\n\n")[0].split())


def tree(root: Path, width: int = 100, package: str = "reports") -> list[str]:
    """``package`` as folders and modules, lines and first docstring line."""
    out = []
    base = root / package
    for folder in [base] + sorted(p for p in base.rglob("*") if p.is_dir()
                                  and (p / "__init__.py").is_file()):
        rel = folder.relative_to(root)
        mods = sorted(folder.glob("*.py"))
        out.append(f"{rel}/  ({sum(map(_lines, mods))} lines)")
        for p in mods:
            text = f"  {p.name:26s}{_lines(p):5d}  {_first_line(p)}"
            out.append(text if len(text) <= width else text[:width - 3] + "...")
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--root", type=Path, default=Path(__file__).resolve().parents[1],
                   help="the checkout to measure (default: this one)")
    p.add_argument("--tree", action="store_true",
                   help="also print reports/ and sim_models/ as trees")
    args = p.parse_args(argv)
    root = args.root.resolve()
    if args.tree:
        for pkg in ("reports", "sim_models"):
            print("\n".join(tree(root, package=pkg)), end="\n\n")
    for pkg in PACKAGES:
        print("\n".join(package_lines(root, pkg)))
    funcs = long_functions(root)
    print(f"functions over {MAX_FUNCTION} lines (analytic, sim_models, reports): {len(funcs)}")
    for n, where in funcs:
        print(f"  {n:4d}  {where}")
    funcs = long_functions(root, packages=OTHER_CODE)
    print(f"functions over {MAX_FUNCTION} lines ({', '.join(OTHER_CODE)}): {len(funcs)}")
    for n, where in funcs:
        print(f"  {n:4d}  {where}")
    nested, total, per = import_share(root)
    print(f"imports inside functions in reports/: {nested} of {total} "
          f"({100 * nested / max(total, 1):.1f}%)")
    for f, n in sorted(per.items(), key=lambda kv: -kv[1])[:10]:
        print(f"  {n:4d}  {f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
