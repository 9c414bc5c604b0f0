"""
``gyro-char swing INPUT --period SECONDS``: swing-stand calibration of one gyro axis.

Writes ``swing.json`` (docs/design.md) and ``swing.png`` in ``--out``; prints the estimates
in the field's units and every note (treatments of the input, warnings) on stderr. The work is
``gyro_char.jobs.swing_job``, which ``gyro-char fleet`` runs too.
"""
from gyro_char.cli import add_common
from gyro_char.jobs import swing_job


def register(subparsers) -> None:
    p = subparsers.add_parser(
        'swing', help='scale-factor error, bias and bias drift from a swing-stand run',
        description=__doc__.strip().splitlines()[0])
    p.add_argument('input', metavar='INPUT', help='bag directory, .mcap, ROS 1 .bag or CSV')
    swing_job.add_options(p)
    add_common(p, default_out='swing_out')
    p.set_defaults(func=run)


def run(args) -> int:
    swing_job.run(args)
    return 0
