"""Subcommands of ``gyro-char``; each module registers its own parser."""
