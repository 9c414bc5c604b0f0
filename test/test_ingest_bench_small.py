"""The ingest benchmark script runs end to end at a small size (speed is measured in bench/)."""
from pathlib import Path
import sys

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / 'bench'))

import bench_ingest  # noqa: E402,I100 - the bench directory is not a package


def test_bench_ingest_small(tmp_path, capsys):
    assert bench_ingest.main(['--n', '12000', '--subset', '1000', '--keep', str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert out.count('bit-for-bit equal on those 1000: True') == 7
