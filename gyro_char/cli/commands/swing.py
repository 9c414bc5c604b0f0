"""
``gyro-char swing INPUT --period SECONDS``: swing-stand calibration of one gyro axis.

Writes ``swing.json`` (docs/design.md) and ``swing.png`` in ``--out``; prints the estimates
in the field's units and every note (treatments of the input, warnings) on stderr. The work is
``gyro_char.jobs.swing_job``, which ``gyro-char fleet`` runs too.
"""
from gyro_char.cli import add_job_command
from gyro_char.jobs import swing_job


def register(subparsers) -> None:
    add_job_command(
        subparsers, 'swing', doc=__doc__, job=swing_job, many=False,
        help_text='scale-factor error, bias and bias drift from a swing-stand run',
        input_help='bag directory, .mcap, ROS 1 .bag or CSV')
