"""The reference robot: the robot end of skidnav's line protocol (docs/protocol.md), in the
subset of Python that MicroPython runs, for robot builders to run on their board or port
(docs/reference-robot.md).

Portable modules (only ``json``, ``time``, ``hashlib``, ``binascii``, ``math``, ``select``,
``socket``, ``os`` and ``sys`` imported; no numpy, threads, dataclasses or typing at run time):

- :mod:`.lines` (framing), :mod:`.messages` (parse and format), :mod:`.hmac_sha256` (RFC
  2104 over ``hashlib.sha256``), :mod:`.authentication` (nonces and MACs),
  :mod:`.host_clock` and :mod:`.rules` (what a robot must do, on decoded messages — the sim
  server's firmware runs these rules too), :mod:`.core` (bytes and time in, bytes and wheel
  speeds out: no I/O);
- :mod:`.interfaces` (the two things a board provides: a :class:`~.interfaces.Robot` and a
  :class:`~.interfaces.Transport`), :mod:`.loop` (the single-threaded polling main loop
  :func:`~.loop.run`), :mod:`.clock` (a running clock from ``time.ticks_ms``),
  :mod:`.simulated_base` (skid-steer kinematics in plain ``math``), :mod:`.tcp` (a TCP
  listener).

CPython only: :mod:`.serial_port` (pyserial), :mod:`.secret_file` (the link secret from a
file or the environment, which skidnav's host reads with it too), :mod:`.cli` and
``__main__`` (``python -m skidnav.realtime.reference_robot --tcp 127.0.0.1:5757``).
"""
