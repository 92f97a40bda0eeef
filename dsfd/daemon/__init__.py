"""The controller daemon (``dsfd run``): the edge around the pure core.

Modules: ``runner`` (start-up, cycle grid, signals, reload, systemd), ``loop`` (one cycle:
read → quality → estimate → calibrate → optimise → safety → write → store), ``clock``,
``quality``, ``weather`` (measured weather → forcing), ``observer``, ``calibration`` (the
on-line calibrator's record and state file), ``safety``, ``storage`` + ``record`` (SQLite),
``notify`` (sd_notify), ``logging_setup`` (structlog), ``summary``, ``sim_plant``
(``--plant sim``), ``bench`` (``dsfd bench daemon``).
"""
