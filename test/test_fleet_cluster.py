"""
``gyro-char fleet --scheduler`` on a cluster started as separate processes on loopback.

``dask scheduler`` and two ``dask worker`` processes; a worker process killed while it runs a
recording (the task is re-run elsewhere and the batch completes); Ctrl-C then the same command
again (finished devices are not recomputed); a manifest of mixed kinds.
"""
import csv
import json
import os
from pathlib import Path
import shutil
import signal
import subprocess
import sys
import threading
import time

from fleet_factory import static_recording, write_csv
from gyro_char.cli import main
from gyro_char.io import write_bag
from gyro_char.sim.config import load
from gyro_char.sim.simulator import simulate_swing
import pytest

BIN = Path(sys.executable).parent
CLI = 'import sys; from gyro_char.cli import main; sys.exit(main())'
N_DEVICES = 5
N_RESUME = 15


def _wait(cond, timeout, what):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        value = cond()
        if value:
            return value
        time.sleep(0.1)
    raise AssertionError(f'timed out waiting for {what}')


@pytest.fixture(scope='module')
def cluster(tmp_path_factory):
    tmp = tmp_path_factory.mktemp('cluster')
    env = dict(os.environ, MPLBACKEND='Agg')
    sched_file = tmp / 'scheduler.json'
    procs = [subprocess.Popen(
        [str(BIN / 'dask'), 'scheduler', '--host', '127.0.0.1', '--port', '0',
         '--no-dashboard', '--scheduler-file', str(sched_file)],
        cwd=tmp, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        address = _wait(lambda: sched_file.exists() and json.loads(
            sched_file.read_text() or '{}').get('address'), 60, 'the scheduler')
        assert address.startswith('tcp://127.0.0.1:')
        for i in range(2):
            procs.append(subprocess.Popen(
                [str(BIN / 'dask'), 'worker', address, '--nthreads', '1', '--host',
                 '127.0.0.1', '--no-dashboard', '--name', f'w{i}',
                 '--local-directory', str(tmp / f'w{i}')],
                cwd=tmp, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        from distributed import Client
        client = Client(address, timeout=30)
        client.wait_for_workers(2, timeout=60)
        data = tmp / 'data'
        data.mkdir()
        for i in range(N_DEVICES):
            write_csv(data / f'imu{i}.csv', static_recording(2.0 + 0.2 * i, 10.0, seed=i,
                                                             duration=300.0))
        yield {'address': address, 'client': client, 'data': data, 'tmp': tmp,
               'scheduler_file': sched_file}
        client.shutdown()  # scheduler and workers stop themselves
    finally:
        for p in procs[::-1]:
            try:
                p.wait(timeout=3)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait(timeout=20)


def _outcomes(out):
    cache = Path(out) / '.fleet-cache'
    return {p.stem: json.loads(p.read_text()) for p in cache.glob('*.json')}


def test_worker_killed_mid_task_is_retried_elsewhere(cluster, tmp_path):
    client, out = cluster['client'], tmp_path / 'out'
    pids = client.run(os.getpid)  # worker address -> pid of the worker process
    argv = ['fleet', str(cluster['data']), '--scheduler', cluster['address'], '--out',
            str(out), '--allan-options=--boot 10', '--quiet']
    result = {}
    runner = threading.Thread(target=lambda: result.update(rc=main(argv)))
    runner.start()
    busy = _wait(lambda: [w for w, keys in client.processing().items() if keys], 120,
                 'a task to start')
    victim = pids[busy[0]]
    os.kill(victim, signal.SIGKILL)  # the nanny starts a new worker process
    runner.join(timeout=300)
    assert not runner.is_alive() and result['rc'] == 0
    done = _outcomes(out)
    assert len(done) == N_DEVICES and all(o['status'] == 'ok' for o in done.values())
    assert victim not in {o['pid'] for o in done.values()}  # nobody finished on the dead one
    for i in range(N_DEVICES):
        assert (out / 'devices' / f'imu{i}' / 'noise.json').is_file()


def test_ctrl_c_then_the_same_command_resumes(cluster, tmp_path):
    # Three times the module's devices, so that Ctrl-C after the first finished one lands while
    # most are still queued however fast the machine is (with five, all could be done by then).
    data, out = tmp_path / 'data', tmp_path / 'out'
    data.mkdir()
    for i in range(N_RESUME):
        shutil.copy(cluster['data'] / f'imu{i % N_DEVICES}.csv', data / f'imu{i}.csv')
    argv = ['fleet', str(data), '--scheduler', cluster['address'], '--out',
            str(out), '--allan-options=--boot 10 --seed 3']
    # As from a terminal: SIGINT at its default, even when this test runs in a background job
    # of a shell without job control (which starts its children with SIGINT ignored).
    proc = subprocess.Popen([sys.executable, '-c', CLI] + argv, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            env=dict(os.environ, MPLBACKEND='Agg'),
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    _wait(lambda: len(_outcomes(out)) >= 1, 180, 'a first finished device')
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and 'the same command resumes' in err, err
    first = _outcomes(out)
    assert 1 <= len(first) < N_RESUME, 'interrupted too late to test the resume'
    stamps = {d: (out / 'devices' / d / 'noise.json').stat().st_mtime_ns for d in first}
    rc = main(argv + ['--quiet'])
    assert rc == 0
    after = _outcomes(out)
    assert len(after) == N_RESUME
    for d in first:  # finished before Ctrl-C: neither recomputed nor rewritten
        assert after[d] == first[d]
        assert (out / 'devices' / d / 'noise.json').stat().st_mtime_ns == stamps[d]


def test_manifest_of_mixed_kinds_equals_the_single_commands(cluster, tmp_path):
    """
    Run allan, swing and diagnose devices in one batch, as their single commands would.

    The cluster is named by its scheduler file; the swing period comes from the manifest; the
    diagnose options (a short, one-channel diagnosis) reach the job.
    """
    data = tmp_path / 'data'
    data.mkdir()
    run = simulate_swing(load(), duration=60.0, seed=3)
    write_bag(str(data / 'stand1'), run.imu, run.encoder)
    shutil.copy(cluster['data'] / 'imu0.csv', data / 'static1.csv')
    (tmp_path / 'fleet.csv').write_text('device,path,kind,period_s,axis\n'
                                        'static1,data/static1.csv,allan,,\n'
                                        'stand1,data/stand1,swing,5.0,\n'
                                        'twin1,data/static1.csv,diagnose,,\n')
    out = tmp_path / 'out'
    diag = ['--channels', 'gyro_x', '--repeats', '4', '--check', '0', '--max-samples', '4096']
    rc = main(['fleet', str(tmp_path / 'fleet.csv'), '--scheduler',
               str(cluster['scheduler_file']), '--out', str(out),
               '--diagnose-options=' + ' '.join(diag), '--quiet'])
    assert rc == 0
    singles = {'static1': (['allan', str(data / 'static1.csv')],
                           ('noise.json', 'allan.json', 'imu.yaml', 'allan.png')),
               'stand1': (['swing', str(data / 'stand1'), '--period', '5'],
                          ('swing.json', 'swing.png')),
               'twin1': (['diagnose', '--kind', 'static', str(data / 'static1.csv')] + diag,
                         ('diagnosis.json', 'diagnosis_gyro_x.png'))}
    for device, (argv, files) in singles.items():
        assert main(argv + ['--out', str(tmp_path / device), '--quiet']) == 0
        for f in files:
            assert (out / 'devices' / device / f).read_bytes() == \
                (tmp_path / device / f).read_bytes(), (device, f)
    with open(out / 'fleet.csv', newline='') as fh:
        rows = list(csv.DictReader(fh))
    swing = json.loads((tmp_path / 'stand1' / 'swing.json').read_text())
    got = {r['quantity']: r for r in rows if r['device'] == 'stand1'}
    assert got['scale_factor_error']['channel'] == 'gyro_x'  # the axis that swings
    for q in ('scale_factor_error', 'bias', 'bias_drift'):
        v, s = swing[q]['value'], swing[q]['sigma']
        assert float(got[q]['value']) == v and float(got[q]['lo68']) == v - s
    diagnosis = json.loads((tmp_path / 'twin1' / 'diagnosis.json').read_text())
    got = {r['quantity']: r for r in rows if r['device'] == 'twin1'}
    assert got['final_gap']['kind'] == 'diagnose' and got['final_gap']['channel'] == 'gyro_x'
    for q in ('baseline_gap', 'final_gap'):
        assert float(got[q]['value']) == diagnosis[q]
    assert float(got['null_gap_q95']['value']) == diagnosis['null_gap']['q95']
    assert got['final_gap']['message'].startswith(f"verdict: {diagnosis['verdict']['code']}; ")
