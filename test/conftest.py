"""Shared test fixtures: where the read-only shared data lives, relative to the repository."""
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
# CI clones the repository with ../shared beside it; the real records are never copied in.
ADIS_DIR = ROOT.parent / 'shared' / 'data' / 'adis16405'


@pytest.fixture(scope='session')
def adis_records():
    """Paths of the two real ADIS16405 static records (session 1, session 2)."""
    paths = [ADIS_DIR / f'adis16405_static_{k}.csv.gz' for k in (1, 2)]
    missing = [str(p) for p in paths if not p.is_file()]
    if missing:
        pytest.fail(f'shared data missing (expected ../shared beside the repo): {missing}')
    return paths
