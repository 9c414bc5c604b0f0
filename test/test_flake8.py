# Lint as the ament linters do: flake8 with ament's configuration (99 columns, single quotes,
# google import order) over the whole package, tests and benchmarks included.
from ament_flake8.main import main_with_errors
import pytest


@pytest.mark.flake8
@pytest.mark.linter
def test_flake8():
    rc, errors = main_with_errors(argv=['gyro_char', 'msg_adapters', 'test', 'bench', 'launch',
                                        'setup.py', 'tasks.py'])
    assert rc == 0, 'Found %d code style errors / warnings:\n' % len(errors) + '\n'.join(errors)
