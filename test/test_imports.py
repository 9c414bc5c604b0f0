"""The import rule of docs/design.md: down the layers only, no cycles, no private names."""
import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ('gyro_char', 'msg_adapters')
# Layer of each top-level part: a module may import its own part or a lower layer only.
LAYER = {
    'gyro_char': 0, 'errors': 0, 'records': 1, 'units': 1, 'progress': 1, 'robust': 1,
    'msg_adapters': 1,
    'io': 2, 'allan': 3, 'swing': 3, 'sim': 4, 'live': 4, 'diagnosis': 5,
    'report': 6, 'jobs': 7, 'fleet': 8, 'cli': 9, 'nodes': 9,
}
FORBIDDEN = {('nodes', 'cli'), ('fleet', 'cli'), ('live', 'io'), ('live', 'sim'),
             ('live', 'diagnosis')}
MAX_LINES = 420


def _modules():
    out = {}
    for pkg in PACKAGES:
        for path in sorted((ROOT / pkg).rglob('*.py')):
            parts = list(path.relative_to(ROOT).with_suffix('').parts)
            if parts[-1] == '__init__':
                parts = parts[:-1]
            out['.'.join(parts)] = path
    return out


MODULES = _modules()


def _resolve(name):
    """Longest known module that ``name`` (a dotted import target) refers to, or None."""
    while name and name not in MODULES:
        name = name.rpartition('.')[0]
    return name or None


def _imports(mod):
    """(target module, imported names) of every import in ``mod``, lazy ones included."""
    tree = ast.parse(MODULES[mod].read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                target = _resolve(a.name)
                if target:
                    yield target, []
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            for a in node.names:
                sub = _resolve(f'{node.module}.{a.name}')
                if sub and sub != _resolve(node.module):
                    yield sub, []  # a submodule imported by name
                elif _resolve(node.module):
                    yield _resolve(node.module), [a.name]


def _part(mod):
    parts = mod.split('.')
    if parts[0] == 'msg_adapters':
        return 'msg_adapters'
    return parts[1] if len(parts) > 1 else 'gyro_char'


GRAPH = {m: sorted({t for t, _ in _imports(m) if t != m}) for m in MODULES}


def test_every_part_has_a_layer():
    assert {_part(m) for m in MODULES} <= set(LAYER), {_part(m) for m in MODULES} - set(LAYER)


def test_no_import_cycles():
    state, stack, cycles = {}, [], []

    def visit(m):
        state[m] = 1
        stack.append(m)
        for t in GRAPH[m]:
            if t.startswith(m + '.') or m.startswith(t + '.'):
                continue  # a package and its own submodules (re-exports)
            if state.get(t) == 1:
                cycles.append(stack[stack.index(t):] + [t])
            elif t not in state:
                visit(t)
        stack.pop()
        state[m] = 2

    for m in GRAPH:
        if m not in state:
            visit(m)
    assert not cycles, 'import cycles:\n' + '\n'.join(' -> '.join(c) for c in cycles)


def test_imports_point_down_the_layers():
    bad = []
    for m, targets in GRAPH.items():
        a = _part(m)
        for t in targets:
            b = _part(t)
            if a == b or b == 'gyro_char':
                continue
            if LAYER[b] > LAYER[a] or (a, b) in FORBIDDEN or (
                    LAYER[b] == LAYER[a] and a != b):
                bad.append(f'{m} -> {t}')
    assert not bad, 'imports against the layer rule:\n' + '\n'.join(bad)


def test_no_private_names_across_modules():
    bad = [f'{m} imports {n} from {t}' for m in MODULES for t, names in _imports(m)
           for n in names if t != m and n.startswith('_')]
    assert not bad, '\n'.join(bad)


@pytest.mark.parametrize('pkg', PACKAGES)
def test_files_stay_small(pkg):
    big = [f'{p.relative_to(ROOT)}: {n} lines' for p in (ROOT / pkg).rglob('*.py')
           if (n := len(p.read_text().splitlines())) > MAX_LINES]
    assert not big, 'split these files:\n' + '\n'.join(big)


def test_the_rule_catches_a_cycle(tmp_path):
    # The checker itself: a two-module cycle is found by the same walk.
    saved = dict(GRAPH)
    try:
        GRAPH['gyro_char.errors'] = ['gyro_char.records']
        with pytest.raises(AssertionError, match='import cycles'):
            test_no_import_cycles()
    finally:
        GRAPH.clear()
        GRAPH.update(saved)
