"""The noise fit's ``interrupt`` hook: a stopping node abandons a long bootstrap between refits."""
from gyro_char.allan.compute import compute
from gyro_char.allan.fit import fit_result
from gyro_char.sim.simulator import simulate_static
import pytest


class Stop(Exception):
    """What the caller raises from its hook."""


@pytest.fixture(scope='module')
def curve():
    return compute(simulate_static(duration=120.0, seed=1).imu, channels=['gyro_x'],
                   m_max=2 ** 10)


def test_the_hook_runs_before_each_refit_and_changes_nothing(curve):
    calls = []
    hooked = fit_result(curve, n_boot=20, seed=3, interrupt=lambda: calls.append(1))
    assert len(calls) == 20
    assert hooked['gyro_x'].to_json() == fit_result(curve, n_boot=20, seed=3)['gyro_x'].to_json()


def test_raising_from_the_hook_abandons_the_fit(curve):
    calls = []

    def stop_at_five():
        calls.append(1)
        if len(calls) == 5:
            raise Stop()
    with pytest.raises(Stop):
        fit_result(curve, n_boot=1000, seed=3, interrupt=stop_at_five)
    assert len(calls) == 5
