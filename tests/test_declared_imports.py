"""Every third-party module the package imports (at the top of a file or inside a function)
comes from a distribution pyproject.toml declares: a fresh install has it. trimesh's own undeclared
import (charset_normalizer, to decode a text STL) is declared here too, since a mesh reaches it.
"""

from __future__ import annotations

import ast
import re
import sys
import tomllib
from importlib.metadata import packages_distributions

from twil_control import PACKAGE_ROOT

SRC = PACKAGE_ROOT / "src" / "twil_control"
#: imported by a dependency that does not declare it, on a path a user's file reaches
UNDECLARED_BY_DEPENDENCIES = {"charset_normalizer": "trimesh decodes a text STL with it"}


def _imported_top_modules() -> dict[str, str]:
    found = {}
    for path in sorted(SRC.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            else:
                continue
            for name in names:
                found.setdefault(name.split(".")[0], str(path.relative_to(SRC)))
    return found


def _declared() -> set[str]:
    """Requirement names of pyproject.toml's [project] dependencies, with the extras they ask
    for (dask[distributed])."""
    with open(PACKAGE_ROOT / "pyproject.toml", "rb") as f:
        requirements = tomllib.load(f)["project"]["dependencies"]
    out = set()
    for req in requirements:
        name, _, extras = re.split(r"[=<>!~;\s]", req)[0].partition("[")
        out.add(name)
        out.update(e.strip() for e in extras.rstrip("]").split(",") if e.strip())
    return out


def _normal(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def test_every_third_party_import_is_declared_in_pyproject():
    declared = {_normal(d) for d in _declared()}
    owners = packages_distributions()
    missing = []
    for module, where in sorted(_imported_top_modules().items()):
        if module in sys.stdlib_module_names or module in ("twil_control", "__future__"):
            continue
        dists = {_normal(d) for d in owners.get(module, [])}
        if not dists & declared:
            missing.append(f"{module} ({where}; from {sorted(dists) or 'no installed distribution'})")
    assert missing == [], "imported but not declared in pyproject.toml: " + ", ".join(missing)


def test_what_dependencies_import_without_declaring_is_declared():
    declared = {_normal(d) for d in _declared()}
    owners = packages_distributions()
    for module in UNDECLARED_BY_DEPENDENCIES:
        assert {_normal(d) for d in owners.get(module, [])} & declared, module
