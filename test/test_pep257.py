# Docstring conventions (pep257, ament's selection) as the ament linters check them.
from ament_pep257.main import main
import pytest


@pytest.mark.linter
@pytest.mark.pep257
def test_pep257():
    rc = main(argv=['gyro_char', 'msg_adapters', 'test', 'bench', 'tasks.py'])
    assert rc == 0, 'Found code style errors / warnings'
