"""
The ``gyro-char`` command: one console script, one module per subcommand.

Each module in ``gyro_char.cli.commands`` provides ``register(subparsers)`` (adding its parser and
setting ``func``) so that the subcommands stay independent. Bad usage or bad input leaves with
exit code 2 and a one-line reason on stderr (docs/design.md), never a traceback.
"""
import argparse
import importlib
import sys
from typing import List, Optional

from gyro_char.errors import InputError

SUBCOMMANDS = ('allan', 'swing', 'simulate', 'diagnose', 'demo', 'fleet')


class _Parser(argparse.ArgumentParser):
    """argparse that reports usage errors as one line and exit code 2."""

    def error(self, message: str) -> None:
        print(f'gyro-char: error: {message}', file=sys.stderr)
        sys.exit(2)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog='gyro-char', description=(
        'Gyro / IMU characterization: Allan-variance noise terms, swing-stand Kalman-filter '
        'calibration, the bench simulator and the sim-to-real diagnosis. INPUT is a ROS 2 bag '
        '(sqlite3 or mcap), a .mcap file, a ROS 1 .bag or a CSV (docs/design.md).'))
    sub = parser.add_subparsers(dest='command', metavar='COMMAND', parser_class=_Parser)
    sub.required = True
    for name in SUBCOMMANDS:
        try:
            module = importlib.import_module(f'gyro_char.cli.commands.{name}')
        except ModuleNotFoundError as exc:
            if exc.name != f'gyro_char.cli.commands.{name}':
                raise
            continue  # subcommand not built yet
        module.register(sub)
    return parser


def add_common(parser: argparse.ArgumentParser, default_out: str) -> None:
    """Options every subcommand accepts."""
    parser.add_argument('--out', default=default_out, help='output directory (created)')
    parser.add_argument('--quiet', action='store_true', help='no progress bars')


def add_job_command(subparsers, name: str, *, doc: str, job, many: bool, help_text: str,
                    input_help: str) -> None:
    """
    Register a subcommand that runs one ``gyro_char.jobs`` module on its INPUT(s).

    The job owns its options (``job.add_options``) and its work (``job.run``), so the command
    and ``gyro-char fleet`` run the same code.
    """
    p = subparsers.add_parser(name, help=help_text, description=doc.strip().splitlines()[0])
    if many:
        p.add_argument('inputs', metavar='INPUT', nargs='+', help=input_help)
    else:
        p.add_argument('input', metavar='INPUT', help=input_help)
    job.add_options(p)
    add_common(p, default_out=f'{name}_out')

    def run(args) -> int:
        job.run(args)
        return 0

    p.set_defaults(func=run)


def main(argv: Optional[List[str]] = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except InputError as exc:
        print(f'gyro-char {args.command}: {exc}', file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print('gyro-char: interrupted', file=sys.stderr)
        return 130


if __name__ == '__main__':
    sys.exit(main())
