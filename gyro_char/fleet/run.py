"""
``gyro-char fleet``: every recording through its single command on Dask, one table, one report.

Plans the devices (``gyro_char.fleet.inputs``), takes finished ones from the resume cache,
runs the rest as Dask tasks (``gyro_char.fleet.engine``, ``gyro_char.fleet.task``), and writes
``devices/<device>/``, ``fleet.csv``, ``fleet.parquet``, ``verdicts.csv`` (with a spec) and
``report.html`` (docs/design.md section 4). Exit code 0 when every device succeeded, 3 when some
are in error (the batch still completes).
"""
import argparse
from dataclasses import dataclass
import os
import shlex
import sys
from typing import Dict, List, Optional, Sequence

from gyro_char.errors import InputError
from gyro_char.fleet.engine import run_tasks
from gyro_char.fleet.inputs import Device, discover
from gyro_char.fleet.spec import judge, limit_for, load_spec
from gyro_char.fleet.store import cache_key, Store
from gyro_char.fleet.table import (COLUMNS, device_rows, device_summaries, OUTLIER_Z,
                                   robust_z, VERDICT_COLUMNS, write_csv, write_parquet)
from gyro_char.fleet.task import package_version, run_device
from gyro_char.jobs import job_module, KINDS
from gyro_char.jobs.base import is_upper_bound
from gyro_char.jobs.dask_client import connect
from gyro_char.progress import progress

EXIT_SOME_ERRORS = 3


class _OptionParser(argparse.ArgumentParser):
    """A command's options for the fleet: a bad option is an InputError (exit 2), not an exit."""

    def error(self, message: str) -> None:
        raise InputError(f'{self.prog}: {message}')


def job_options(kind: str, text: str, overrides: Optional[Dict] = None) -> Dict:
    """
    Parse a ``--<kind>-options`` string with the option definitions of ``gyro-char <kind>``.

    A device's manifest overrides (``period``, ``axis``) are added as options; the result is
    the options as a dict.

    Raises
    ------
    InputError
        On an option the command does not have or a bad value.

    """
    parser = _OptionParser(prog=f'--{kind}-options', add_help=False)
    job_module(kind).add_options(parser, require=False)
    tokens = shlex.split(text or '')
    for name, value in (overrides or {}).items():
        tokens += [f'--{name}', str(value)]
    return vars(parser.parse_args(tokens))


@dataclass
class FleetConfig:
    """What ``gyro-char fleet`` was asked to do."""

    inputs: Sequence[str]
    kind: str = 'allan'
    out: str = 'fleet_out'
    spec: Optional[str] = None
    workers: Optional[int] = None
    scheduler: Optional[str] = None
    quiet: bool = False
    job_options: Dict[str, str] = None


@dataclass
class Planned:
    """One device with its parsed options and cache key."""

    device: Device
    options: Dict
    key: str


def plan(cfg: FleetConfig) -> List[Planned]:
    """Return the devices with their options (bad usage raises InputError before any work)."""
    texts = cfg.job_options or {}
    for kind in KINDS:
        job_options(kind, texts.get(kind, ''))  # a bad option fails fast, whatever the inputs
    planned = []
    for dev in discover(cfg.inputs, cfg.kind):
        over = dev.overrides if dev.kind != 'allan' else {}
        options = job_options(dev.kind, texts.get(dev.kind, ''), over)
        planned.append(Planned(dev, options, cache_key(dev.path, dev.kind, options)))
    return planned


def run_fleet(cfg: FleetConfig) -> int:
    """Run the fleet; return the exit code (0 all ok, 3 some devices in error)."""
    if cfg.workers is not None and cfg.workers < 1:
        raise InputError('--workers must be >= 1')
    spec = load_spec(cfg.spec) if cfg.spec else None
    planned = plan(cfg)
    store = Store(cfg.out)
    outcomes: Dict[str, Dict] = {}
    todo = []
    for p in planned:
        hit = store.cached(p.device.device, p.key)
        if hit is not None:
            outcomes[p.device.device] = dict(hit, cached=True)
        else:
            todo.append(p)
    keys = {p.device.device: p.key for p in planned}
    bar = progress(total=len(planned), desc='devices', quiet=cfg.quiet, unit='device')
    bar.update(len(outcomes))

    mine, warned = package_version(), set()

    def on_result(result: Dict) -> None:
        theirs = result.get('version', mine)
        if theirs != mine and theirs not in warned:  # e.g. a worker of an existing cluster
            warned.add(theirs)
            print(f'warning: a worker runs gyro_char {theirs}, this client {mine}: results '
                  'may differ from the single command here', file=sys.stderr)
        store.save(result, keys[result['device']])
        # the files are on disk now: keep only the small part in memory
        outcomes[result['device']] = {k: v for k, v in result.items()
                                      if k not in ('files', 'log')}
        bar.update(1)

    if todo:
        workers = cfg.workers or (None if cfg.scheduler else os.cpu_count() or 1)
        tasks = [(f'gyro-char-fleet-{p.device.device}-{p.key[:16]}',
                  (p.device.device, p.device.path, p.device.kind, p.options)) for p in todo]
        try:
            with connect(workers, cfg.scheduler) as client:
                run_tasks(client, run_device, tasks, on_result)
        except KeyboardInterrupt:
            bar.close()
            print(f'gyro-char fleet: interrupted with {len(outcomes)} of {len(planned)} '
                  'devices done; the same command resumes', file=sys.stderr)
            raise
    bar.close()
    return finish(cfg, planned, outcomes, spec, store)


def finish(cfg: FleetConfig, planned: List[Planned], outcomes: Dict[str, Dict], spec,
           store: Store) -> int:
    """Write the tables, the verdicts and the report; print the summary; return the exit code."""
    from gyro_char.report.fleet_html import write_report

    rows, verdicts = [], []
    for p in planned:
        d = p.device
        o = outcomes[d.device]
        mine = device_rows(d.device, d.path, d.kind, o['status'], o['message'],
                           o['measurements'])
        if spec is not None:
            verdict, reasons, passes = judge(spec, d.kind, o['status'], o['message'],
                                             o['measurements'])
            for r, ok in zip(mine, passes if o['status'] == 'ok' else [False]):
                r['pass'] = ok  # an error device's one row: False
            verdicts.append({'device': d.device, 'verdict': verdict, 'reasons': reasons})
        rows.extend(mine)
    columns = COLUMNS + (('pass',) if spec is not None else ())
    write_csv(os.path.join(cfg.out, 'fleet.csv'), rows, columns)
    write_parquet(os.path.join(cfg.out, 'fleet.parquet'), rows, columns)
    if spec is not None:
        write_csv(os.path.join(cfg.out, 'verdicts.csv'), verdicts, VERDICT_COLUMNS)
    devices = device_summaries(rows, robust_z(rows), verdicts if spec is not None else None)
    for d in devices:
        folder = store.device_dir(d['device'])
        d['plots'] = sorted(p.name for p in folder.glob('*.png')) if folder.is_dir() else []

    def limit_of(kind, channel, quantity):
        lim = limit_for(spec or {}, kind, channel, quantity)
        return None if lim is None else (lim.unit, lim.bounds)

    marked = [dict(r, bound=is_upper_bound(r)) for r in rows]
    write_report(os.path.join(cfg.out, 'report.html'), devices, marked, limit_of, OUTLIER_Z)
    errors = [p.device.device for p in planned if outcomes[p.device.device]['status'] != 'ok']
    cached = sum(1 for o in outcomes.values() if o.get('cached'))
    line = (f'{len(planned)} devices: {len(planned) - len(errors)} ok, {len(errors)} in error'
            f' ({cached} from the cache)')
    if spec is not None:
        count = {v: sum(1 for x in verdicts if x['verdict'] == v) for v in ('pass', 'fail')}
        line += f'; spec: {count["pass"]} pass, {count["fail"]} fail'
    print(line)
    for p in planned:
        o = outcomes[p.device.device]
        if o['status'] != 'ok':
            print(f'error: {p.device.device}: {o["message"]}', file=sys.stderr)
    print(f'wrote {cfg.out}/fleet.csv, fleet.parquet, '
          + ('verdicts.csv, ' if spec is not None else '') + 'report.html, devices/')
    return EXIT_SOME_ERRORS if errors else 0
