"""Logging for the daemon: structlog in front, the standard library (pymodbus, drivers) behind
the same renderer.

* Under systemd (stdout is not a terminal) every line is one JSON object for journald and
  log shippers; in a terminal :mod:`dsfd.daemon.console` prints one aligned line per cycle
  and marks the events (``dsfd run --log-format json|console`` chooses either).
* ``panel`` and ``cycle`` are context variables merged into every line, structlog's and the
  standard library's alike (``merge_contextvars`` runs first in the shared chain).
  ``asyncio.to_thread`` copies the context, so lines from the calibration and optimisation
  worker threads carry the cycle too (a bare ``run_in_executor`` would not).
* pymodbus logs through the stdlib logger ``pymodbus.logging``; a
  :class:`structlog.stdlib.ProcessorFormatter` renders those records with the same
  processors (ecosystem notes §5).

Call :func:`configure_logging` once at start; tests may call it again with their own stream.
"""

from __future__ import annotations

import logging
import sys
from typing import Any, TextIO

import structlog
from structlog.contextvars import bind_contextvars, bound_contextvars, clear_contextvars
from structlog.typing import EventDict

from dsfd.daemon.console import CONSOLE_ONLY, CycleConsoleRenderer
from dsfd.drivers.modbus_link import configure_pymodbus_logging

__all__ = [
    "bind_contextvars",
    "bound_contextvars",
    "clear_contextvars",
    "configure_logging",
    "get_logger",
]


def configure_logging(*, stream: TextIO | None = None, json: bool | None = None,
                      level: int = logging.INFO, pymodbus_level: int = logging.ERROR) -> None:
    """Route structlog and stdlib logging to ``stream`` (default stdout) through one renderer.

    Parameters
    ----------
    stream : text stream, optional
        Where lines go (stdout: journald captures it under systemd).
    json : bool, optional
        JSON lines (True) or console lines (False); default: JSON unless ``stream`` is a tty.
        Colours only when ``stream`` is a tty.
    level : int
        Threshold of dsfd's own loggers.
    pymodbus_level : int
        Threshold of pymodbus (it logs every timed-out request at ERROR with a frame dump and
        each refused connect at WARNING; the drivers report both as reading qualities).
    """
    stream = sys.stdout if stream is None else stream
    json_mode = (not _isatty(stream)) if json is None else json
    shared: list[structlog.types.Processor] = [
        structlog.contextvars.merge_contextvars,
        structlog.stdlib.add_log_level,
        structlog.stdlib.add_logger_name,
        structlog.processors.TimeStamper(fmt="iso", utc=True),
    ]
    structlog.configure(
        processors=[structlog.stdlib.filter_by_level, *shared,
                    structlog.stdlib.PositionalArgumentsFormatter(),
                    structlog.stdlib.ProcessorFormatter.wrap_for_formatter],
        logger_factory=structlog.stdlib.LoggerFactory(),
        wrapper_class=structlog.stdlib.BoundLogger,
        # Not cached: a reconfiguration (tests, a second run in one process) must take effect.
        cache_logger_on_first_use=False,
    )
    renderer: structlog.types.Processor
    tail: list[structlog.types.Processor] = []
    if json_mode:
        tail += [_drop_console_only, structlog.processors.dict_tracebacks]
        renderer = structlog.processors.JSONRenderer()
    else:
        tail.append(structlog.processors.format_exc_info)
        renderer = CycleConsoleRenderer(colors=_isatty(stream))
    handler = logging.StreamHandler(stream)
    handler.setFormatter(structlog.stdlib.ProcessorFormatter(
        foreign_pre_chain=shared,
        processors=[structlog.stdlib.ProcessorFormatter.remove_processors_meta, *tail,
                    renderer]))
    root = logging.getLogger()
    for old in list(root.handlers):
        root.removeHandler(old)
    root.addHandler(handler)
    root.setLevel(level)
    configure_pymodbus_logging(level=pymodbus_level)


def _drop_console_only(_logger: Any, _name: str, event_dict: EventDict) -> EventDict:
    """Keys meant for the console renderer only: the JSON lines stay as they were."""
    for key in CONSOLE_ONLY:
        event_dict.pop(key, None)
    return event_dict


def get_logger(name: str) -> structlog.stdlib.BoundLogger:
    """A structlog logger named like a stdlib one (``dsfd.daemon.loop``)."""
    return structlog.stdlib.get_logger(name)


def _isatty(stream: TextIO) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False
