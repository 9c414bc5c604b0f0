# gyro-char diagnose --scheduler: the channels run as tasks on a real Dask cluster (worker
# processes on loopback) and give exactly what the in-process run gives.
import json

from gyro_char.cli import main
import numpy as np
import pytest


def _write_csv(path, n=4096, dt=0.01, seed=3):
    rng = np.random.default_rng(seed)
    t = np.arange(n) * dt
    x = 0.4 * rng.standard_normal(n) + 0.3 * np.sin(2 * np.pi * 17.0 * t)
    y = 0.4 * rng.standard_normal(n)
    with open(path, 'w') as fh:
        fh.write('t_s,gyro_x_dps,gyro_y_dps\n')
        for row in zip(t, np.round(x / 0.05) * 0.05, np.round(y / 0.05) * 0.05):
            fh.write('%.2f,%.2f,%.2f\n' % row)


def test_scheduler_runs_the_channels_as_tasks_and_matches_the_local_run(tmp_path):
    distributed = pytest.importorskip('distributed')
    csv = tmp_path / 'rec.csv'
    _write_csv(csv)
    common = ['diagnose', '--kind', 'static', str(csv), '--repeats', '4', '--check', '0',
              '--quiet']
    assert main(common + ['--out', str(tmp_path / 'local')]) == 0
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        assert main(common + ['--out', str(tmp_path / 'dask'),
                              '--scheduler', cluster.scheduler_address]) == 0
    local = json.loads((tmp_path / 'local' / 'diagnosis.json').read_text())
    remote = json.loads((tmp_path / 'dask' / 'diagnosis.json').read_text())
    for ch in ('gyro_x', 'gyro_y'):
        a, b = local['per_channel'][ch], remote['per_channel'][ch]
        assert a['selected_effects'] == b['selected_effects']
        assert a['final_gap'] == pytest.approx(b['final_gap'], rel=1e-9)
        assert (tmp_path / 'dask' / f'diagnosis_{ch}.png').stat().st_size > 10_000
    assert local['per_channel']['gyro_x']['selected_effects'][:1] == ['vibration']
    assert local['analysed']['samples'] == 4096


def test_unreachable_scheduler_is_a_one_line_error(tmp_path, capsys):
    pytest.importorskip('distributed')
    csv = tmp_path / 'rec.csv'
    _write_csv(csv, n=2048)
    import dask
    # Dask's own connect timeout (30 s by default) is how long a scheduler is tried.
    with dask.config.set({'distributed.comm.timeouts.connect': '3s'}):
        rc = main(['diagnose', '--kind', 'static', str(csv), '--out', str(tmp_path / 'o'),
                   '--scheduler', 'tcp://127.0.0.1:9', '--quiet'])
    assert rc == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and 'scheduler' in err[0]
