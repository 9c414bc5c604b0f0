"""
What every job shares: where its printed lines go and the tidy form of its results.

The CLI prints to the terminal; the fleet runs jobs in worker processes and keeps their lines
in a per-device log, so a job prints through a ``Console`` instead of ``sys.stdout`` directly.
"""
import sys
from typing import Optional, TextIO


class Console:
    """Output streams of a job: ``out`` for results, ``err`` for notes (default: the terminal)."""

    def __init__(self, out: Optional[TextIO] = None, err: Optional[TextIO] = None):
        self._out, self._err = out, err

    @property
    def out(self) -> TextIO:
        """Return the result stream (``sys.stdout`` at the time of the call unless given)."""
        return self._out if self._out is not None else sys.stdout

    @property
    def err(self) -> TextIO:
        """Return the note stream (``sys.stderr`` at the time of the call unless given)."""
        return self._err if self._err is not None else sys.stderr


def measurement(channel: str, quantity: str, value: float, si_unit: str,
                lo68: Optional[float] = None, hi68: Optional[float] = None,
                message: str = '') -> dict:
    """
    One tidy measurement: a quantity of a channel in SI with its 68 % interval.

    ``message`` carries what a reader of the number must know (e.g. that an unresolved noise
    term is an upper bound).
    """
    return {'channel': channel, 'quantity': quantity, 'value': float(value),
            'si_unit': si_unit, 'lo68': None if lo68 is None else float(lo68),
            'hi68': None if hi68 is None else float(hi68), 'message': message}


UPPER_BOUND = 'unresolved: the value is an upper bound'


def is_upper_bound(row: dict) -> bool:
    """Tell whether a measurement's value is only an upper bound (an unresolved term)."""
    return UPPER_BOUND in (row.get('message') or '')
