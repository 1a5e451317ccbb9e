"""Errors a user can cause. The CLI prints them as one line and exits with code 2."""


class UserError(Exception):
    """Bad input from the user (a config, map file, saved file, wire message, argument).

    The message is one line naming the problem, e.g. ``"maps/a.txt:3:7: start on a wall"``.
    """


class CorruptFileError(UserError):
    """A saved file that is truncated, corrupt, or from an incompatible version."""
