"""The controller daemon (``dsfd run``): the edge around the pure core.

Modules: ``runner`` (start-up, cycle grid, signals, reload, systemd), ``startup`` (what is
checked before anything is opened), ``state`` (what a start takes over from the state
directory), ``loop`` (one cycle: read → quality → estimate →
calibrate → optimise → safety → write → store) with ``device_io`` (the read and write
stages), ``outcome`` and ``jobs``, ``clock``, ``quality``, ``weather`` (measured weather →
forcing), ``observer``, ``calibration`` (the on-line calibrator's record and state file),
``safety``, ``hold`` + ``manual`` (the manual hold and operator commands) with ``commands``
(their validation), ``record`` (SQLite rows), ``metrics`` (the Prometheus file),
``notify`` (sd_notify), ``logging_setup`` (structlog), ``summary``. The simulated plant of
``--plant sim`` is :mod:`dsfd.sim.daemon_plant`, ``dsfd bench daemon`` is
:mod:`dsfd.bench.daemon`.
"""
