"""The one place numba is configured.

Every compiled hot loop in skidnav is plain Python over NumPy arrays, decorated with :func:`jit`.
With ``NUMBA_DISABLE_JIT=1`` in the environment numba leaves the functions as they are, so the
same code runs interpreted and must give bit-identical results (the test suite checks it).

The on-disk cache of compiled code is kept per version of the source: numba checks only the
time stamp of the file of the function it loads, so a kernel whose callee, or a constant it
froze, changed in another file would load its old machine code without a word. skidnav keeps
the cache in ``NUMBA_CACHE_DIR`` (default ``$XDG_CACHE_HOME/skidnav/numba``, else
``~/.cache/skidnav/numba``) under :func:`source_fingerprint`, so any change of any module
compiles everything afresh once (``make clean-cache`` removes old versions).
"""

from __future__ import annotations

import functools
import hashlib
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

import numba
from numba.extending import overload, register_jitable

F = TypeVar("F", bound=Callable[..., Any])
PACKAGE = Path(__file__).resolve().parent
"""The skidnav package's folder, whose modules :func:`source_fingerprint` reads."""


def source_fingerprint(package: Path = PACKAGE) -> str:
    """16 hex digits of the SHA-256 of every ``.py`` file under ``package`` (path relative to
    it, then its bytes, in sorted path order): equal for equal sources wherever they lie."""
    digest = hashlib.sha256()
    for path in sorted(package.rglob("*.py")):
        digest.update(path.relative_to(package).as_posix().encode() + b"\0")
        digest.update(path.read_bytes() + b"\0")
    return digest.hexdigest()[:16]


def cache_folder(environment: dict[str, str], fingerprint: str) -> Path:
    """Where numba caches the compiled code of the sources of ``fingerprint``: the folder of
    that name under ``NUMBA_CACHE_DIR`` of ``environment`` (or that folder itself, as set for
    a worker process by its parent), else under the user's cache folder."""
    chosen = environment.get("NUMBA_CACHE_DIR")
    if chosen:
        return Path(chosen) if Path(chosen).name == fingerprint else Path(chosen) / fingerprint
    base = environment.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "skidnav" / "numba" / fingerprint


def _use_versioned_cache() -> None:
    """Point numba's cache (this process's and its children's) at :func:`cache_folder`."""
    folder = str(cache_folder(dict(os.environ), source_fingerprint()))
    os.environ["NUMBA_CACHE_DIR"] = folder  # numba reads it again before each compilation
    numba.config.CACHE_DIR = folder  # type: ignore[attr-defined]


_use_versioned_cache()


KERNELS: list[Any] = []
"""Every function made by :func:`jit` and :func:`inline_jit`, as imported so far (numba's
dispatchers; the plain functions with ``NUMBA_DISABLE_JIT=1``)."""


def _kept(kernel: F) -> F:
    KERNELS.append(kernel)
    return kernel


def jit(function: F) -> F:
    """Compile ``function`` in nopython mode with an on-disk cache (no fastmath: results must match
    the interpreter bit for bit)."""
    return _kept(numba.njit(cache=True, nogil=True)(function))  # type: ignore[return-value]


def vector_jit(function: F) -> F:
    """Like :func:`jit`, with NumPy's error model: a float division by zero gives ±inf or NaN
    instead of raising, so that the compiler can vectorise a loop that divides (the kernels of
    the fast MPPI path, :mod:`skidnav.agents.mpc.single`; none of them divides by zero)."""
    return _kept(numba.njit(cache=True, nogil=True, error_model="numpy")(function))  # type: ignore[return-value]


def vector_inline_jit(function: F) -> F:
    """:func:`vector_jit`, inlined into compiled callers like :func:`inline_jit`."""
    compiled = numba.njit(cache=True, nogil=True, error_model="numpy", inline="always")
    return _kept(compiled(function))  # type: ignore[return-value]


def inline_jit(function: F) -> F:
    """Like :func:`jit`, but inlined into compiled callers at the numba IR level.

    Used for the small helpers of the hot loops: a non-inlined call that receives arrays (or a
    Generator) costs ~30–300 ns in numba 0.68 (reference counting of every array argument), more
    than the helper's work. Inlining does not remove all of it: every array (or tuple of arrays)
    bound to a helper parameter, and every view such as ``q[state]``, is still reference-counted
    each call unless numba can prune the pair. Hot helpers therefore index ``q[state, action]``
    (no row views) and take only the few arrays they read. Called from Python it behaves like
    any compiled function, and with ``NUMBA_DISABLE_JIT=1`` it is the plain function.
    """
    return _kept(numba.njit(inline="always", cache=True, nogil=True)(function))  # type: ignore[return-value]


def elementwise(function: F) -> F:
    """A helper of plain arithmetic that compiled callers compile into their own code (numba's
    ``register_jitable``) and that stays the plain function when called from Python: the same
    formula runs on float scalars in a compiled loop and on whole NumPy arrays (the fast
    MPPI path and its NumPy twin, :mod:`skidnav.agents.mpc.single`)."""
    jitable: F = register_jitable(inline="always", error_model="numpy")(function)
    return jitable


def compiled_as(compiled: Callable[..., Any]) -> Callable[[F], F]:
    """Decorator: compiled callers of the decorated function run ``compiled`` (of the same
    arguments) in its place, Python callers the function itself — for a NumPy function on arrays
    whose scalar equivalent numba compiles to a vectorisable instruction (``np.sqrt`` and
    ``math.sqrt``, ``np.where`` and a conditional expression)."""

    def decorate(function: F) -> F:
        typing = functools.wraps(compiled)(lambda *args: compiled)  # its signature
        overload(function, inline="always", jit_options={"error_model": "numpy"})(typing)
        return function

    return decorate


def dispatch_on_type(registry: dict[type, Any]) -> Callable[[F], F]:
    """Decorator for a generic function ``generic(first, *rest)`` that calls
    ``registry[type(first)](first, *rest)`` (``first`` a NamedTuple, the values compiled
    functions): called from Python it is that lookup; called from compiled code numba makes the
    choice while compiling, from the NamedTuple class of ``first``, so the compiled caller takes
    no function as an argument and caches on disk like any other. The small glue compiled for
    each class is not cached itself (its index would name classes of any module)."""

    def decorate(generic: F) -> F:
        def typing(first: Any, *rest: Any) -> Any:
            kernel = registry.get(getattr(first, "instance_class", type(None)))
            if kernel is None:
                return None  # numba reports the missing implementation

            def implementation(first: Any, *rest: Any) -> Any:
                return kernel(first, *rest)

            return implementation

        overload(generic, jit_options={"nogil": True})(typing)
        return generic

    return decorate


def uncached(function: Any) -> Any:
    """A second compiled version of a :func:`jit` function, without the disk cache, for
    arguments of types defined outside skidnav (an agent in a test or a notebook): numba's cache
    index pickles the types of every signature it holds, so one such entry would make the index
    unreadable to every process that cannot import that type's module."""
    python_function = getattr(function, "py_func", function)
    return numba.njit(cache=False, nogil=True)(python_function)


def jit_disabled() -> bool:
    """True when ``NUMBA_DISABLE_JIT`` is set, i.e. kernels run as plain Python."""
    return bool(getattr(numba.config, "DISABLE_JIT", False))


def _has_code(kernel: Any) -> bool:
    """True if ``kernel`` needs no compiling: it is compiled in this process, or numba's on-disk
    cache of this source version has an index for it, or it is not a dispatcher (JIT off)."""
    signatures = getattr(kernel, "signatures", None)
    if signatures is None or signatures:
        return True
    try:
        index = Path(kernel._cache._cache_file._index_path)  # numba's cache (0.6x) internals
    except AttributeError:  # another numba: say nothing rather than guess
        return True
    return index.exists()


def first_compile(packages: tuple[str, ...]) -> bool:
    """True when code of one of ``packages`` (module name prefixes, e.g.
    ``"skidnav.agents.tabular"``) will be compiled before it runs: none of its imported kernels
    (:data:`KERNELS`) is compiled in this process or cached on disk for this source version —
    the first run after installing or changing skidnav. A cheap check by file names: it misses
    the shorter compile of a kernel for new argument types (a new agent of a family whose other
    agents have run) and says nothing with ``NUMBA_DISABLE_JIT=1``."""
    for package in packages:
        kernels = [k for k in KERNELS if getattr(k, "__module__", "").startswith(package + ".")]
        if kernels and not any(_has_code(kernel) for kernel in kernels):
            return True
    return False
