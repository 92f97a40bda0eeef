"""The controller daemon (``dsfd run``): the edge around the pure core.

Modules: ``runner`` (start-up, cycle grid, signals, reload, systemd), ``startup`` (what is
checked before anything is opened), ``loop`` (one cycle: read → quality → estimate →
calibrate → optimise → safety → write → store) with ``outcome`` and ``jobs``, ``clock``,
``quality``, ``weather`` (measured weather → forcing), ``observer``, ``calibration`` (the
on-line calibrator's record and state file), ``safety``, ``hold`` + ``manual`` (the manual
hold and operator commands) with ``commands`` (their validation), ``record`` (SQLite rows),
``notify`` (sd_notify), ``logging_setup`` (structlog), ``summary``, ``sim_plant``
(``--plant sim``), ``bench`` (``dsfd bench daemon``).
"""
