"""
``gyro-char fleet INPUT...``: many recordings through one command on Dask, one table, one report.

Runs ``allan``, ``swing`` or ``diagnose`` on every recording found in the INPUTs (directories
searched recursively, files, or a manifest CSV ``device,path,kind[,period_s,axis]``) as Dask
tasks: a local cluster of ``--workers`` processes, or an existing cluster with ``--scheduler``.
Writes ``devices/<device>/`` (the single command's files), ``fleet.csv`` and ``fleet.parquet``
(tidy), ``verdicts.csv`` (with ``--spec``) and ``report.html`` in ``--out`` (docs/fleet.md).
Exit 0 when every device succeeded, 3 when some are in error, 2 for bad usage.
"""
from gyro_char.cli import add_common
from gyro_char.jobs import KINDS


def register(subparsers) -> None:
    p = subparsers.add_parser(
        'fleet', help='characterize many IMUs at once on Dask: tables, verdicts, one report',
        description=__doc__.strip().splitlines()[0])
    p.add_argument('inputs', metavar='INPUT', nargs='+',
                   help='directory (searched recursively), recording, or manifest CSV')
    p.add_argument('--kind', choices=KINDS, default='allan',
                   help="command run on each recording (a manifest's kind column wins)")
    p.add_argument('--spec', default=None, metavar='YAML',
                   help='datasheet limits; adds verdicts.csv and a pass column (docs/fleet.md)')
    where = p.add_mutually_exclusive_group()
    where.add_argument('--workers', type=int, default=None, metavar='N',
                       help='local worker processes (default: the core count)')
    where.add_argument('--scheduler', default=None, metavar='ADDRESS',
                       help='an existing Dask cluster: tcp://HOST:PORT or a scheduler file')
    for kind in KINDS:
        p.add_argument(f'--{kind}-options', default='', metavar='"OPTIONS"',
                       help=f'options of gyro-char {kind} for its recordings, in one string '
                            f'(write --{kind}-options="--opt value")')
    add_common(p, default_out='fleet_out')
    p.set_defaults(func=run)


def run(args) -> int:
    from gyro_char.fleet.run import FleetConfig, run_fleet

    return run_fleet(FleetConfig(
        inputs=args.inputs, kind=args.kind, out=args.out, spec=args.spec, workers=args.workers,
        scheduler=args.scheduler, quiet=args.quiet,
        job_options={k: getattr(args, f'{k}_options') for k in KINDS}))
