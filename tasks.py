#!/usr/bin/env python3
"""
One entry point for the README's two commands: ``demo`` and ``test``.

Creates ``.venv`` beside this file on first use (Python 3.11 and the package registries are
all it needs), installs the pinned requirements and the package in editable mode, then runs the
requested task inside that environment. Re-runs reuse the environment unless the requirement
files changed.
"""
import hashlib
import os
from pathlib import Path
import subprocess
import sys

ROOT = Path(__file__).resolve().parent
VENV = ROOT / '.venv'
PY = VENV / 'bin' / 'python'
STAMP = VENV / '.gyro_char_installed'


def _requirements_digest() -> str:
    h = hashlib.sha256()
    for name in ('requirements-dev.txt', 'setup.py', 'setup.cfg'):
        h.update((ROOT / name).read_bytes())
    return h.hexdigest()


def ensure_env() -> None:
    digest = _requirements_digest()
    if STAMP.exists() and STAMP.read_text() == digest:
        return
    if not PY.exists():
        print('[tasks] creating virtual environment in .venv', flush=True)
        subprocess.run([sys.executable, '-m', 'venv', str(VENV)], check=True)
    pip = [str(PY), '-m', 'pip', 'install', '--disable-pip-version-check', '-q']
    print('[tasks] installing pinned requirements (first run takes a minute)', flush=True)
    subprocess.run(pip + ['--upgrade', 'pip'], check=True)
    subprocess.run(pip + ['-r', str(ROOT / 'requirements-dev.txt')], check=True)
    subprocess.run(pip + ['--no-deps', '-e', str(ROOT)], check=True)
    STAMP.write_text(digest)


def _ros_env() -> dict:
    env = dict(os.environ)
    # Keep every DDS packet on this machine.
    env.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    env.setdefault('ROS_DOMAIN_ID', '42')
    env['PATH'] = str(VENV / 'bin') + os.pathsep + env.get('PATH', '')
    env.setdefault('MPLBACKEND', 'Agg')
    return env


def _workers(extra: list) -> list:
    """
    pytest-xdist options: one worker a core (at most 4), whole files to one worker.

    A file keeps its tests in order and its own ROS domain ids (``test/node_harness.py``), so
    node tests of different files never share a DDS domain. ``-n`` given by hand wins.
    """
    if any(a.startswith(('-n', '--numprocesses')) for a in extra):
        return []
    n = min(os.cpu_count() or 1, 4)
    return ['-n', str(n), '--dist', 'loadfile'] if n > 1 else []


def main(argv: list) -> int:
    if not argv or argv[0] not in ('demo', 'test'):
        print('usage: python3 tasks.py {demo|test} [extra args]', file=sys.stderr)
        return 2
    ensure_env()
    task, extra = argv[0], argv[1:]
    if task == 'demo':
        cmd = [str(VENV / 'bin' / 'gyro-char'), 'demo'] + extra
    else:
        cmd = [str(PY), '-m', 'pytest', '-q', str(ROOT / 'test')] + _workers(extra) + extra
    rc = subprocess.run(cmd, cwd=ROOT, env=_ros_env()).returncode
    if task == 'test' and rc == 5:
        # pytest's 'no tests collected' must never pass as green.
        print('[tasks] pytest collected no tests', file=sys.stderr)
        return 1
    return rc


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
