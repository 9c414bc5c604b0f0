"""
``gyro-char allan INPUT``: Allan variance and IEEE 952 noise terms of a static record.

Writes in ``--out`` (docs/design.md): ``allan.json`` (tau, overlapping ADEV and its 68 %
interval per channel), ``noise.json`` (N, B, K, Q, R per channel, SI, with 68 % intervals and
``resolved``), ``imu.yaml`` (Kalibr noise model: worst axis, per-axis values too) and
``allan.png``. Prints the human table (deg/sqrt(h), deg/h, ...) and every note about the input.
The work is ``gyro_char.jobs.allan_job``, which ``gyro-char fleet`` runs too.
"""
from gyro_char.cli import add_job_command
from gyro_char.jobs import allan_job


def register(subparsers) -> None:
    add_job_command(
        subparsers, 'allan', doc=__doc__, job=allan_job, many=False,
        help_text='Allan variance + IEEE 952 noise terms (N, B, K, Q, R) of a static record',
        input_help='bag directory, .mcap, ROS 1 .bag or CSV')
