"""The package's shape: no import cycle (deferred imports included), pipelines import each other only
where the architecture says, no private name imported across modules, nothing installed at top level."""
import ast
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
# source folder -> installed package name (pyproject's package-dir)
SOURCES = {"autobones": ROOT / "autobones", "autobones.cli": ROOT / "cli",
           "autobones.generic_rig": ROOT / "generic_rig"}
PIPELINES = ("placement", "rig_transfer", "rig_building", "landmarks", "expressions")
# the only pipeline-to-pipeline imports: placing on a transferred rig, finding landmarks for a
# transfer, labelling a generic rig's depth groups as placing does, and proposing landmarks by the
# generic head's fit (landmarks.assist uses the correspondence, never rig_transfer.pipeline)
ALLOWED_BETWEEN = {("placement", "rig_transfer"), ("rig_transfer", "landmarks"), ("rig_building", "placement"),
                   ("landmarks", "rig_transfer")}


def _modules():
    """{dotted module name: (path, is_package)} of everything that gets installed."""
    out = {}
    for package, folder in SOURCES.items():
        for path in sorted(folder.rglob("*.py")):
            rel = path.relative_to(folder).with_suffix("").parts
            if package == "autobones" and rel[0] in ("cli", "generic_rig"):
                continue
            is_pkg = rel[-1] == "__init__"
            name = ".".join((package,) + (rel[:-1] if is_pkg else rel))
            out[name] = (path, is_pkg)
    return out


MODULES = _modules()


def _imports(name):
    """Every import statement of a module (top level and inside functions) as
    (target module, imported names, line)."""
    path, is_pkg = MODULES[name]
    package = name if is_pkg else name.rsplit(".", 1)[0]
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found += [(a.name, [], node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module
            found.append((target, [a.name for a in node.names], node.lineno))
    return found


def _edges():
    """(importer, imported module, line) for imports of our own modules; ``from pkg import mod``
    counts as an import of the submodule."""
    edges = []
    for name in MODULES:
        for target, names, line in _imports(name):
            if target not in MODULES:
                continue
            subs = [f"{target}.{n}" for n in names if f"{target}.{n}" in MODULES]
            edges += [(name, t, line) for t in (subs or [target])]
    return edges


def _pipeline(name):
    parts = name.split(".")
    return parts[1] if len(parts) > 1 and parts[1] in PIPELINES else None


def test_the_import_graph_has_no_cycle():
    import numpy as np
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    names = sorted(MODULES)
    at = {m: i for i, m in enumerate(names)}
    pairs = np.array([(at[a], at[b]) for a, b, _ in _edges() if a != b]).reshape(-1, 2)
    graph = sp.csr_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(names),) * 2)
    _, comp = connected_components(graph, directed=True, connection="strong")
    cycles = [sorted(names[i] for i in np.flatnonzero(comp == c))
              for c in np.unique(comp) if (comp == c).sum() > 1]
    assert not cycles, f"import cycles: {cycles}"


def test_pipelines_import_each_other_only_as_the_architecture_says():
    bad = []
    for a, b, line in _edges():
        pa, pb = _pipeline(a), _pipeline(b)
        if pa and pb and pa != pb and (pa, pb) not in ALLOWED_BETWEEN:
            bad.append(f"{a}:{line} imports {b}")
        if a.startswith("autobones.geometry") and not (b.startswith("autobones.geometry") or b == "autobones.errors"):
            bad.append(f"{a}:{line} imports {b} (geometry/ is the bottom layer)")
    assert not bad, "\n".join(bad)


def test_no_private_name_is_imported_across_modules():
    bad = [f"{name}:{line} imports {target}.{n}"
           for name in MODULES for target, names, line in _imports(name)
           if target in MODULES for n in names if n.startswith("_") and n != "__version__"]
    assert not bad, "\n".join(bad)


def test_no_public_function_shadows_a_submodule():
    import importlib
    import types

    shadowed = []
    for name in MODULES:
        if not MODULES[name][1]:
            continue
        package = importlib.import_module(name)
        for child in MODULES:
            if child.rsplit(".", 1)[0] == name and child != name:
                leaf = child.rsplit(".", 1)[1]
                value = getattr(package, leaf, None)
                if value is not None and not isinstance(value, types.ModuleType):
                    shadowed.append(f"{name}.{leaf} is a {type(value).__name__}, not the submodule {child}")
    assert not shadowed, "\n".join(shadowed)


def test_nothing_installs_as_a_top_level_package_but_autobones():
    conf = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    assert all(p == "autobones" or p.startswith("autobones.") for p in conf["packages"])
    declared = set(conf["packages"])
    on_disk = {m for m, (_, is_pkg) in MODULES.items() if is_pkg}
    assert on_disk <= declared, f"packages not listed in pyproject.toml: {sorted(on_disk - declared)}"
    for package, folder in conf.get("package-dir", {}).items():
        assert (ROOT / folder / "__init__.py").is_file() and package.startswith("autobones.")


@pytest.mark.parametrize("entry", ["autobones.cli.main"])
def test_python_dash_m_and_the_console_script_reach_the_same_main(entry):
    import importlib
    import subprocess
    import sys

    assert callable(importlib.import_module(entry).main)
    out = subprocess.run([sys.executable, "-m", "autobones", "--help"], capture_output=True, text=True,
                         timeout=120, cwd="/")
    assert out.returncode == 0 and "place" in out.stdout and "transfer" in out.stdout, out.stderr[-2000:]
