"""Load a ``bench/`` script as a module (the bench directory is not a package)."""
import importlib.util
from pathlib import Path
import sys
from types import ModuleType

BENCH = Path(__file__).resolve().parents[1] / 'bench'


def load(name: str) -> ModuleType:
    """Return ``bench/<name>.py`` imported under its own name (its bench imports resolved)."""
    if str(BENCH) not in sys.path:
        sys.path.append(str(BENCH))
    spec = importlib.util.spec_from_file_location(name, BENCH / f'{name}.py')
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod
