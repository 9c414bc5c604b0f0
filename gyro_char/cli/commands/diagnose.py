"""
``gyro-char diagnose --kind KIND INPUT...``: where the sim-to-real gap lies and what explains it.

Fits the paper's baseline model to each gyro channel of the input record(s), compares them with
the model on a battery of observables (static: closed-form expectations over the whole record,
checked by simulated twins; swing: simulated twins), ranks the catalogue effects and adds them
greedily; writes ``diagnosis.json`` (docs/design.md) and ``diagnosis_<channel>.png`` in
``--out``. The work, options and outputs are described in ``gyro_char.jobs.diagnose_job`` and
``gyro_char.jobs.diagnose_static``; ``gyro-char fleet`` runs them too.
"""
from gyro_char.cli import add_common
from gyro_char.jobs import diagnose_job


def register(subparsers) -> None:
    p = subparsers.add_parser(
        'diagnose', help='sim-to-real gap: where it lies, which unmodelled effects explain it',
        description=__doc__.strip().splitlines()[0])
    p.add_argument('inputs', metavar='INPUT', nargs='+',
                   help='bag directory, .mcap, ROS 1 .bag or CSV (same sensor, same rate)')
    diagnose_job.add_options(p)
    add_common(p, default_out='diagnose_out')
    p.set_defaults(func=run)


def run(args) -> int:
    diagnose_job.run(args)
    return 0
