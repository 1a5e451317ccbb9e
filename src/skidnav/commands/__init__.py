"""Command-line subcommands, one module each; :mod:`skidnav.cli` lists them.

Each module defines ``add_parser(subparsers)`` which adds its subcommand and sets
``func=callable(args) -> int`` as the parser default.
"""
