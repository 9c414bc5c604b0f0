"""
Where the held-out shape sets live: one file a set beside the harnesses, named by a letter.

``<prefix>.py`` is the first set (letter ``bare``), ``<prefix>_<letter>.py`` the others; a
new set is its file alone, both harnesses find it (``letters``, ``module``).
"""
from pathlib import Path

BENCH = Path(__file__).resolve().parent


def letters(prefix: str, bare: str) -> list:
    """Return the letters of the sets ``<prefix>[_<letter>].py`` present in the bench folder."""
    return sorted(bare if p.stem == prefix else p.stem[len(prefix) + 1:]
                  for p in BENCH.glob(f'{prefix}*.py'))


def module(prefix: str, letter: str, bare: str) -> str:
    """Return the module name of set ``letter``."""
    return prefix if letter == bare else f'{prefix}_{letter}'
