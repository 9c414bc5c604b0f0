"""
Error types of gyro_char, kept in a module with no internal imports (the bottom layer).

Every front door turns an ``InputError`` into a one-line message: the CLI exits with code 2, the
nodes log it and keep running.
"""


class InputError(ValueError):
    """Bad or unusable input; the CLI turns it into a one-line message and exit code 2."""
