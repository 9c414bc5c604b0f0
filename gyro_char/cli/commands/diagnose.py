"""
``gyro-char diagnose --kind KIND INPUT...``: where the sim-to-real gap lies and what explains it.

Fits the paper's baseline model to each gyro channel of the input record(s), compares them with
the model on a battery of observables (static: closed-form expectations over the whole record,
checked by simulated twins; swing: simulated twins), ranks the catalogue effects and adds them
greedily; writes ``diagnosis.json`` (docs/design.md) and ``diagnosis_<channel>.png`` in
``--out``. The work, options and outputs are described in ``gyro_char.jobs.diagnose_job`` and
``gyro_char.jobs.diagnose_static``; ``gyro-char fleet`` runs them too.
"""
from gyro_char.cli import add_job_command
from gyro_char.jobs import diagnose_job


def register(subparsers) -> None:
    add_job_command(
        subparsers, 'diagnose', doc=__doc__, job=diagnose_job, many=True,
        help_text='sim-to-real gap: where it lies, which unmodelled effects explain it',
        input_help='bag directory, .mcap, ROS 1 .bag or CSV (same sensor, same rate)')
