"""``dsfd fleet``: what every panel on a broker is doing, one line per panel.

Subscribes to ``<base>/+/state`` and ``<base>/+/availability`` (both retained, so a new
subscriber gets every panel's last state and availability at once) for a few seconds and
tabulates the newest message per panel. Panels must use base topics one level under
``<base>`` (the default ``dsfd/<panel id>`` does).
"""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from dsfd.integrations.mqtt.link import BrokerLink, new_client, reason_text

__all__ = ["FleetError", "PanelView", "collect", "fleet_rows", "format_table"]


class FleetError(RuntimeError):
    """The broker could not be reached or refused the connection."""


@dataclass
class PanelView:
    """The newest state and availability seen for one panel."""

    panel: str
    online: bool | None = None
    state: dict[str, Any] = field(default_factory=dict)
    malformed: int = 0


def collect(link: BrokerLink, *, base: str, wait_s: float) -> dict[str, PanelView]:
    """Panels under ``base`` on the broker, after listening for ``wait_s`` seconds."""
    client = new_client(link, client_id="")  # the broker assigns one (clean session)
    panels: dict[str, PanelView] = {}
    lock = threading.Lock()
    ready = threading.Event()
    outcome: dict[str, str] = {}

    def on_connect(c: Any, _u: Any, _f: Any, reason_code: Any, _p: Any) -> None:
        if reason_code.is_failure:
            outcome["refused"] = reason_text(reason_code)
            ready.set()
            return
        c.subscribe([(f"{base}/+/state", 1), (f"{base}/+/availability", 1)])

    def on_subscribe(_c: Any, _u: Any, _mid: int, _codes: Any, _p: Any) -> None:
        ready.set()

    def on_disconnect(_c: Any, _u: Any, _f: Any, reason_code: Any, _p: Any) -> None:
        outcome.setdefault("lost", reason_text(reason_code))
        ready.set()

    def on_message(_c: Any, _u: Any, msg: Any) -> None:
        parts = msg.topic.split("/")
        name, kind = parts[-2], parts[-1]
        with lock:
            view = panels.setdefault(name, PanelView(name))
            if kind == "availability":
                text = msg.payload.decode("utf-8", "replace").strip()
                view.online = {"online": True, "offline": False}.get(text)
                return
            try:
                state = json.loads(msg.payload)
            except ValueError:
                view.malformed += 1
                return
            if isinstance(state, dict):
                view.state = state
            else:
                view.malformed += 1

    client.on_connect, client.on_subscribe = on_connect, on_subscribe
    client.on_disconnect, client.on_message = on_disconnect, on_message
    try:
        client.connect(link.host, link.port, keepalive=link.keepalive_s)
    except (OSError, ValueError) as exc:
        raise FleetError(f"cannot connect to the MQTT broker {link.address}: {exc}") from exc
    client.loop_start()
    try:
        if not ready.wait(15.0):
            raise FleetError(f"no answer from the MQTT broker {link.address} within 15 s")
        if "refused" in outcome:
            raise FleetError(f"the MQTT broker {link.address} refused the connection: "
                             f"{outcome['refused']}")
        if "lost" in outcome:
            raise FleetError(f"the MQTT broker {link.address} closed the connection: "
                             f"{outcome['lost']}")
        time.sleep(wait_s)
    finally:
        client.disconnect()
        client.loop_stop()
    with lock:
        return dict(sorted(panels.items()))


def fleet_rows(panels: Mapping[str, PanelView]) -> list[dict[str, Any]]:
    """One flat record per panel (the ``--json`` output)."""
    out = []
    for name, view in panels.items():
        s = view.state
        cmd = s.get("command") if isinstance(s.get("command"), dict) else {}
        faults = s.get("faults") if isinstance(s.get("faults"), list) else []
        out.append({
            "panel": s.get("panel", name), "online": view.online, "mode": s.get("mode"),
            "set_by": s.get("set_by"), "regime": cmd.get("regime"),
            "regime_name": cmd.get("regime_name"), "louver_deg": cmd.get("louver_deg"),
            "damper_pct": cmd.get("damper_pct"),
            "hold": (s.get("hold_source") or "yes") if s.get("hold") else None,
            "hold_until_utc": s.get("hold_until_utc"), "faults": faults,
            "last_seen_utc": s.get("time_utc"), "decision_ms": s.get("decision_ms"),
            "run": s.get("run"), "cycle": s.get("cycle"), "malformed_messages": view.malformed,
        })
    return out


_COLUMNS = ("panel", "online", "mode", "regime", "louver", "damper", "hold", "faults",
            "last seen (UTC)", "decision")


def format_table(rows: Sequence[Mapping[str, Any]]) -> str:
    """The human table: one line per panel, columns sized to their contents."""
    lines = [_COLUMNS]
    for r in rows:
        regime = "-" if r["regime"] is None else (
            f"{r['regime']} {r['regime_name']}" if r["regime_name"] else str(r["regime"]))
        hold = "-" if not r["hold"] else (
            f"{r['hold']} until {r['hold_until_utc']}" if r["hold_until_utc"]
            else str(r["hold"]))
        lines.append((
            str(r["panel"]), {True: "yes", False: "no", None: "?"}[r["online"]],
            str(r["mode"] or "-"), regime, _num(r["louver_deg"], "{:+.0f} deg"),
            _num(r["damper_pct"], "{:.0f} %"), hold,
            "; ".join(map(str, r["faults"])) or "-",
            str(r["last_seen_utc"] or "-"), _num(r["decision_ms"], "{:.1f} ms")))
    widths = [max(len(line[i]) for line in lines) for i in range(len(_COLUMNS))]
    return "\n".join("  ".join(cell.ljust(w) for cell, w in zip(line, widths, strict=True))
                     .rstrip() for line in lines)


def _num(value: Any, fmt: str) -> str:
    return "-" if not isinstance(value, int | float) else fmt.format(value)
