"""
One recording -> the single command's files + a tidy result (the layer under cli/ and fleet/).

Each ``<kind>_job`` module holds the options of its ``gyro-char <kind>`` subcommand
(``add_options``) and the function that runs it on one recording (``run``), so the CLI
subcommands and the fleet call the same code. ``run(args, console)`` writes the command's files
in ``args.out``, prints what the command prints through ``console`` and returns the tidy
measurements (``gyro_char.jobs.base.measurement`` dicts).
"""
import importlib

KINDS = ('allan', 'swing', 'diagnose')


def job_module(kind: str):
    """Return the job module of a kind (``allan``, ``swing`` or ``diagnose``)."""
    if kind not in KINDS:
        raise ValueError(f'no job {kind!r}; jobs are {", ".join(KINDS)}')
    return importlib.import_module(f'gyro_char.jobs.{kind}_job')
