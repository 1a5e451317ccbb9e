"""Errors a user can cause, and failed runs. The CLI prints them as one line and exits with code 2
(a user error) or 1 (failed runs)."""

EXCERPT_CHARS = 40
"""Most characters of a file's contents an error message quotes."""


class UserError(Exception):
    """Bad input from the user (a config, map file, saved file, wire message, argument).

    The message is one line naming the problem, e.g. ``"maps/a.txt:3:7: start on a wall"``.
    """


LEAD_CHARS = 160
"""Most characters of a wrapped error's own message (:func:`within`), so that its places still
fit in the one line :func:`first_line` prints."""


class ConfigError(UserError, ValueError):
    """A config's error, its one line leading with what is wrong (the key, the value and its
    limit), the places it was found in after it (outermost first: file, table), then the
    details, so that neither a long path nor the cut of :func:`first_line` hides what is
    wrong::

        expected alpha in (0, 1], got 5 in configs/quick.toml: agent 'dyna-full'

    A :class:`ValueError` too, for the callers that catch a config class's ValueError.

    Args:
        lead: the problem, naming the key or value (``"expected alpha in (0, 1], got 5"``).
        places: where it was found, outermost first (each wrapper adds its own, :func:`within`).
        detail: what would be right (the known keys), last.
    """

    def __init__(self, lead: str, places: tuple[str, ...] = (), detail: str = "") -> None:
        self.lead, self.places, self.detail = lead, places, detail
        where = f" in {': '.join(places)}" if places else ""
        super().__init__(f"{lead}{where}" + (f" ({detail})" if detail else ""))


class ConfigKeyError(ConfigError):
    """A config's key that is wrong (unknown, misspelt), named first::

    unknown key 'planing_steps' in configs/quick.toml: agent 'dyna-full' (did you mean
    'planning_steps'? expected one of …)
    """


class SetupError(UserError):
    """What this installation lacks (an extra not installed), not a fault of the file it was
    met in: :func:`within` leaves it as it is, its one line ending with the command that fixes
    it."""


def within(error: BaseException, place: str) -> UserError:
    """``error`` (a config's) found in ``place`` (a file, a table) as one :class:`ConfigError`
    that still leads with what is wrong and takes ``place`` as its outermost place; a
    :class:`SetupError` unchanged.

    >>> str(within(ConfigKeyError("unknown key 'x'", ("[run]",), "expected y"), "a.toml"))
    "unknown key 'x' in a.toml: [run] (expected y)"
    >>> str(within(ValueError("expected seeds ≥ 1, got 0"), "a.toml"))
    'expected seeds ≥ 1, got 0 in a.toml'
    >>> str(within(SetupError('agent needs the deep extra: pip install "skidnav[deep]"'), "a"))
    'agent needs the deep extra: pip install "skidnav[deep]"'
    """
    if isinstance(error, SetupError):
        return error
    if isinstance(error, ConfigError):
        return type(error)(error.lead, (place, *error.places), error.detail)
    lines = str(error).splitlines()
    lead = lines[0] if lines else type(error).__name__
    return ConfigError(lead[:LEAD_CHARS] + ("…" if len(lead) > LEAD_CHARS else ""), (place,))


class CorruptFileError(UserError):
    """A saved file that is truncated, corrupt, or from an incompatible version."""


class RunsFailedError(Exception):
    """Runs of a sweep that raised while the others finished and were kept (each failure was
    logged in one line as it happened; :mod:`skidnav.experiments.failures`). The CLI prints the
    message as one line and exits with :data:`EXIT_RUNS_FAILED`."""


class Interrupted(KeyboardInterrupt):
    """A sweep stopped by Ctrl-C or SIGTERM, with what it had saved: ``saved`` of ``total`` runs
    in the results directory ``where`` (a rerun of the same command resumes from them)."""

    def __init__(self, saved: int, total: int, where: str) -> None:
        super().__init__(f"{saved} of {total} runs saved in {where}")
        self.saved, self.total, self.where = saved, total, where


EXIT_RUNS_FAILED = 1
"""Exit code of a command whose sweep had failed runs (2 is a user error)."""


def excerpt(text: str | bytes, limit: int = EXCERPT_CHARS) -> str:
    """A short, safe quotation of untrusted text for an error message: its first ``limit``
    characters, ``repr``-escaped (so control characters, NUL bytes and newlines show as escapes
    and the message stays one line), with ``…`` when cut.

    >>> print(excerpt("PATH=/usr/bin\\x00HOME=/root\\x00SECRET=" + "x" * 100))
    'PATH=/usr/bin\\x00HOME=/root\\x00SECRET=xxxxxxxx'…
    >>> print(excerpt(b"ab\\ncd"))
    'ab\\ncd'
    """
    if isinstance(text, bytes):
        text = text[: limit * 4].decode("utf-8", errors="replace")
    cut = len(text) > limit
    return repr(text[:limit]) + ("…" if cut else "")


def shown(value: object) -> str:
    """``repr(value)`` of a value read from a file, for an error message: whole up to
    :data:`EXCERPT_CHARS` characters, else cut by :func:`excerpt`.

    >>> shown(1.5), shown("x" * 100)
    ('1.5', '"\\'xxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx"…')
    """
    text = repr(value)
    return text if len(text) <= EXCERPT_CHARS else excerpt(text)


def first_line(error: BaseException, limit: int = 200) -> str:
    """The first line of an error's message, control characters escaped and cut to ``limit``
    characters (messages may quote a file), or the error's type when it has no message.

    >>> first_line(ValueError("bad value 'x\\x00y'\\nsecond line"))
    "bad value 'x\\\\x00y'"
    """
    text = str(error)
    if not text:
        return type(error).__name__
    line = repr(text.splitlines()[0])[1:-1]
    return line[:limit] + ("…" if len(line) > limit else "")


def unknown_arguments(words: list[str]) -> str:
    """The command-line ``words`` a parser did not know, for its error message: each option by
    its name, and what follows an unknown option (its ``=`` value, the words up to the next
    option) as ``…``: a prefix or a misspelling of ``--secret-file`` must not print the secret
    typed after it.

    >>> unknown_arguments(["--secret", "hunter2", "--token=abc", "extra.toml"])
    '--secret … --token=… extra.toml'
    """
    shown_words, after_option = [], False
    for word in words:
        if word.startswith("-") and len(word) > 1:
            name, equals, _ = word.partition("=")
            shown_words.append(name + ("=…" if equals else ""))
            after_option = not equals
        elif after_option:
            if shown_words[-1] != "…":
                shown_words.append("…")
        else:
            shown_words.append(word)
    return " ".join(shown_words)
