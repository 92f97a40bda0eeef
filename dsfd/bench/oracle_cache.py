"""Stored plant-oracle results of ``dsfd bench closed-loop`` (``--oracle-cache FILE``).

The plant oracle decides by rollouts of the truth plant itself: about 40 CPU minutes per
simulated day here, and its result for a case and seed does not depend on the controller
being judged. A JSON file keeps each result with what it was computed from, so a table of
several seeds can be built over several sessions and re-scored whenever ``mpc`` changes.

An entry is used only when everything that determines the oracle's run is the same:
the case, the seed, the scored days and warm-up, the weather record, the panel
configuration (a SHA-256 digest of its canonical form, without the sections the plant oracle
never reads: :data:`NOT_READ_BY_ORACLE`) and :data:`ORACLE_VERSION`. Change
:data:`ORACLE_VERSION` with any change of the truth plant, the plant oracle or the closed
loop's set-up: the file cannot see code. Each entry also records the commit that produced it
(``git rev-parse HEAD`` where the bench runs in a checkout) and when.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import subprocess
import time
from pathlib import Path

from dsfd.config.panel import PanelConfig

__all__ = ["NOT_READ_BY_ORACLE", "ORACLE_VERSION", "OracleCache", "config_digest"]

#: Version of what the plant oracle's result depends on in code (the truth plant, the plant
#: oracle, the closed-loop set-up). Entries of another version are ignored.
ORACLE_VERSION = "2026-11-29 plant oracle within the comfort limits (issue 35)"


#: Sections of the panel configuration left out of the digest. The plant oracle plans with
#: the plant's true parameters on a frozen calibration stage that never fits nor tracks
#: offsets (:class:`dsfd.sim.oracle_controllers.FrozenCalibration`), so ``calibration`` does
#: not reach its commands; nor do the integrations. A calibration setting tried on ``mpc``
#: thus keeps the oracle figures already computed.
NOT_READ_BY_ORACLE = ("calibration", "mqtt", "bacnet")
#: Settings within a section left out likewise: whether the optimiser's rollouts take the
#: calibration's heat-flux offsets changes nothing for a stage whose offsets are zero.
NOT_READ_BY_ORACLE_SETTINGS = {"control": ("heat_offsets",)}


def config_digest(cfg: PanelConfig) -> str:
    """SHA-256 of the panel configuration's canonical JSON form without
    :data:`NOT_READ_BY_ORACLE` and :data:`NOT_READ_BY_ORACLE_SETTINGS` (first 16 hex
    digits)."""
    doc = {k: v for k, v in dataclasses.asdict(cfg).items() if k not in NOT_READ_BY_ORACLE}
    for section, names in NOT_READ_BY_ORACLE_SETTINGS.items():
        doc[section] = {k: v for k, v in doc[section].items() if k not in names}
    text = json.dumps(doc, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _commit() -> str:
    try:
        done = subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True,
                              timeout=5, cwd=Path(__file__).resolve().parent, check=False)
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return done.stdout.strip() if done.returncode == 0 else "unknown"


class OracleCache:
    """The plant-oracle figures kept in ``path`` (created on the first store)."""

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self._entries: dict[str, dict] = {}
        if self.path.exists():
            data = json.loads(self.path.read_text(encoding="utf-8"))
            if not isinstance(data, dict) or not isinstance(data.get("entries"), dict):
                raise ValueError(f"{self.path}: not a plant-oracle cache (no 'entries' object)")
            self._entries = data["entries"]

    @staticmethod
    def key(*, case: str, seed: int, days: float, warmup_h: float, weather: str,
            digest: str) -> str:
        return (f"{case}|seed {seed}|days {days:g}|warm-up {warmup_h:g} h|{weather}|"
                f"config {digest}|{ORACLE_VERSION}")

    def get(self, key: str) -> dict[str, float] | None:
        """The stored scored figures (``J_kwh``, heat terms, …) of ``key``, or None."""
        entry = self._entries.get(key)
        return None if entry is None else dict(entry["figures"])

    def put(self, key: str, figures: dict[str, float]) -> None:
        """Store ``figures`` under ``key`` with the commit and time, and write the file
        (replaced atomically: a reader never sees half a file)."""
        self._entries[key] = {"figures": figures, "commit": _commit(),
                              "stored_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ",
                                                          time.gmtime())}
        self.path.parent.mkdir(parents=True, exist_ok=True)
        tmp = self.path.with_name(self.path.name + ".tmp")
        tmp.write_text(json.dumps({"oracle_version": ORACLE_VERSION,
                                   "entries": self._entries}, indent=1, sort_keys=True))
        os.replace(tmp, self.path)
