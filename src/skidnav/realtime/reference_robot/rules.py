"""What a robot must do with the messages of one connection (docs/protocol.md, "What a robot
must do" and "Stale commands: the stall rule"), free of any I/O.

:meth:`Rules.receive` takes one *batch* — everything read at once, each item a decoded message
(a ``dict``, :mod:`.messages`) or the :class:`~.lines.LineError` of a line that was none — and
:meth:`Rules.watch` the passing of time; both return the *effects* to carry out, in order:

- ``("send", message)``: send ``message`` (a ``dict`` without ``seq``: the sender numbers it);
- ``("wheels", omega_left, omega_right)``: hold these wheel speeds [rad/s];
- ``("stop",)``: zero both wheels now, dropping anything queued for them;
- ``("note", event, fields)``: something worth a log line (``hello``, ``cmd``, ``stop``,
  ``superseded``, ``error``, ``peer_error``, ``lease``, ``watchdog``);
- ``("hang_up", reason)``: close the connection (failed authentication, idle host).

The rules, in the order they apply: a line that is no message is answered ``error`` with its
code and stops the wheels (``auth`` also hangs up, and nothing more is taken from the
connection); a message whose ``seq`` does not exceed the previous one's is refused
(``replay``); nothing but ``hello`` is taken before ``hello`` (``state``); of a batch only its
last ``cmd``, ``stop`` or bad line sets the wheels (earlier ``cmd``\\ s are dropped unanswered),
every ``stop`` is answered ``stopped`` and every ``heartbeat`` with one of the robot's own; a
``cmd`` beyond the wheel-speed limit is refused (``range``), and so is one older than its
``ttl`` when read (``expired``: its ``stamp`` mapped onto the robot's clock by
:class:`~.host_clock.HostClock`). A command holds the wheels for ``min(ttl, max_lease)`` after it
was read, whatever its ``stamp``; :meth:`Rules.watch`, called every control period, stops the
wheels when that lease ends or when no valid message came for ``link_timeout``, and hangs up
after ``idle_timeout``. Every time is the robot's own running clock [s], one that keeps counting
while the robot is stalled.
"""

from .host_clock import HostClock

MAX_LEASE_LIMIT = 5.0
"""Largest lease a robot can be configured to grant [s wall]: however it is set, no command
keeps the wheels turning longer than this after it arrived."""
TYPE_CHECKING = False  # MicroPython has no typing module: its names are for the type checker
if TYPE_CHECKING:
    from typing import Any

    from .messages import Message

    Effect = tuple[Any, ...]


class Rules:
    """The robot's side of the protocol on one connection (see module doc).

    Args:
        name: the robot's name, sent in its ``hello``.
        period: its control period [s], sent in its ``hello``.
        wheel_limit: the largest wheel speed it runs [rad/s]; beyond it, ``error`` ``range``.
        now: the time of connection [s, robot clock].
        max_lease: the longest a command holds the wheels after it was read [s].
        link_timeout: quiet time [s] after which the wheels stop.
        idle_timeout: quiet time [s] after which the host is dropped (≥ ``link_timeout``).
        nonce: the robot's ``hello`` nonce (hex), empty without authentication.
    """

    def __init__(
        self,
        name: str,
        period: float,
        wheel_limit: float,
        now: float,
        max_lease: float = 0.5,
        link_timeout: float = 0.5,
        idle_timeout: float = 2.0,
        nonce: str = "",
    ) -> None:
        if not (max_lease > 0 and 0 < link_timeout <= idle_timeout):
            raise ValueError("expected max_lease > 0 and 0 < link_timeout <= idle_timeout")
        self.name, self.period, self.wheel_limit, self.nonce = name, period, wheel_limit, nonce
        self.max_lease, self.link_timeout, self.idle_timeout = max_lease, link_timeout, idle_timeout
        self.greeted = False
        self.closed = False  # after a failed authentication nothing more is taken
        self.last_valid = now  # when the newest valid message arrived [s]
        self.last_seq: int | None = None  # the newest seq taken from the host
        self.lease: float | None = None  # when the wheels' command runs out [s]
        self.engaged = False  # wheels set by a command and not stopped since
        self.clock = HostClock()

    # --- effects --------------------------------------------------------------------------
    def _stop(self, effects: "list[Effect]") -> None:
        self.lease, self.engaged = None, False
        effects.append(("stop",))

    def _reject(self, effects: "list[Effect]", code: str, text: str) -> None:
        """Bad input: stop the wheels and answer ``error``."""
        self._stop(effects)
        effects.append(("note", "error", {"code": code, "message": text}))
        effects.append(("send", {"type": "error", "code": code, "message": text[:200]}))

    # --- a batch --------------------------------------------------------------------------
    def receive(self, items: "list[Any]", now: float) -> "list[Effect]":
        """The effects of one batch read at ``now`` [s] (see module doc)."""
        effects: list[Effect] = []
        motions = [i for i, item in enumerate(items) if _is_motion(item)]
        newest = motions[-1] if motions else -1
        for index, item in enumerate(items):
            if self.closed:
                break
            if not isinstance(item, dict):
                self._refuse_line(effects, item)
            elif not self._in_order(effects, item):
                continue
            elif item["type"] == "hello":
                self._hello(effects, item, now)
            elif not self.greeted:
                self._reject(effects, "state", item["type"] + " before hello")
            else:
                self.last_valid = now
                self._handle(effects, item, now, index < newest)
        return effects

    def _refuse_line(self, effects: "list[Effect]", error: "Any") -> None:
        """A line that is no message; after a failed authentication, hang up."""
        self._reject(effects, error.code, str(error))
        if error.code == "auth":
            self.closed = True
            effects.append(("hang_up", "authentication failed: " + str(error)))

    def _in_order(self, effects: "list[Effect]", message: "Message") -> bool:
        """The seq rule: True if ``message`` comes after the last one taken, else refuse it."""
        last, seq = self.last_seq, message["seq"]
        if last is not None and seq <= last:
            text = "{} {} after {}: seq must increase".format(message["type"], seq, last)
            self._reject(effects, "replay", text)
            return False
        self.last_seq = seq
        return True

    def _hello(self, effects: "list[Effect]", message: "Message", now: float) -> None:
        self.greeted, self.last_valid = True, now
        effects.append(("note", "hello", {"name": message["name"]}))
        hello = {"type": "hello", "name": self.name, "period": self.period, "nonce": self.nonce}
        effects.append(("send", hello))

    def _handle(
        self, effects: "list[Effect]", message: "Message", now: float, superseded: bool
    ) -> None:
        kind = message["type"]
        if kind in ("cmd", "heartbeat"):
            self.clock.observe(message["stamp"], now)
        if kind == "cmd":
            self._command(effects, message, now, superseded)
        elif kind == "stop":
            self._stop(effects)
            effects.append(("note", "stop", {"seq": message["seq"]}))
            effects.append(("send", {"type": "stopped", "ack": message["seq"]}))
        elif kind == "heartbeat":
            effects.append(("send", {"type": "heartbeat", "stamp": now}))
        elif kind == "error":
            note = {"code": message["code"], "message": message["message"]}
            effects.append(("note", "peer_error", note))
        else:
            self._reject(effects, "state", "unexpected " + kind + " from host")

    def _command(
        self, effects: "list[Effect]", message: "Message", now: float, superseded: bool
    ) -> None:
        """Run a ``cmd`` unless superseded, beyond the limit or stale; its lease is
        ``min(ttl, max_lease)`` from ``now``."""
        seq, stamp = message["seq"], message["stamp"]
        if superseded:
            effects.append(("note", "superseded", {"seq": seq, "stamp": stamp}))
            return
        left, right, limit = message["omega_left"], message["omega_right"], self.wheel_limit
        if max(abs(left), abs(right)) > limit:
            text = f"cmd {seq}: a wheel speed beyond ±{limit!r} rad/s"
            self._reject(effects, "range", text)
            return
        ttl = min(message["ttl"], self.max_lease)
        age = self.clock.age(stamp, now)
        if age >= ttl:
            text = f"cmd {seq} read {age - ttl:.3f} s after its deadline"
            self._reject(effects, "expired", text)
            return
        self.lease, self.engaged = now + ttl, True
        effects.append(("wheels", left, right))
        note = {"seq": seq, "omega_left": left, "omega_right": right, "stamp": stamp}
        note.update({"age": age, "lease": ttl})
        effects.append(("note", "cmd", note))
        effects.append(("send", {"type": "ack", "ack": seq}))

    # --- time -----------------------------------------------------------------------------
    def watch(self, now: float) -> "list[Effect]":
        """The robot's own safety at ``now`` [s], every control period before the wheel speeds
        go to the motors: the lease and a quiet link stop the wheels, an idle host is hung up."""
        effects: list[Effect] = []
        if self.lease is not None and now >= self.lease:
            if self.engaged:
                effects.append(("note", "lease", {"late": now - self.lease}))
            self._stop(effects)
        quiet = now - self.last_valid
        if quiet > self.idle_timeout:
            effects.append(("hang_up", f"no valid message for {quiet:.3f} s"))
        elif quiet > self.link_timeout:
            if self.engaged:
                effects.append(("note", "watchdog", {}))
            self._stop(effects)
        return effects


def _is_motion(item: object) -> bool:
    """What sets the wheels: a ``cmd``, a ``stop``, or a bad line (which stops them)."""
    return not isinstance(item, dict) or item["type"] in ("cmd", "stop")
