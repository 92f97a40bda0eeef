"""The MQTT publisher of one panel: a thread beside the control loop, fed from the database.

The loop never waits for it. After each stored cycle the runner calls
:meth:`MqttPublisher.cycle_stored`, which only sets an event; the publisher's own thread then
reads the new cycles from the database (:class:`~dsfd.integrations.mqtt.outbox.Outbox`) and
hands them to paho-mqtt's network thread (``loop_start``). A slow, absent or refusing broker
costs the loop nothing.

Delivery: every state message goes out with QoS 1 and the retain flag; at most
:data:`WINDOW` are unacknowledged at a time. The delivery cursor in ``mqtt_cursor`` moves to
the last cycle whose PUBACK arrived with all before it acknowledged too. When the connection
drops, the unacknowledged ones are sent again, in order, on the next connection (QoS-1
redelivery: a subscriber may see a cycle twice, never a gap); after a daemon restart the
same happens from the saved cursor. Cycles older than ``mqtt.backlog_max_age_h`` (relative to
the newest stored cycle) are passed over and counted as expired.

Connection: a fresh paho client per attempt with the last will ``<base>/availability`` =
``offline`` (retained); on CONNACK it publishes ``online`` (retained), the Home Assistant
discovery configs (retained) and the last day's KPIs. Failed attempts back off
exponentially with jitter (:class:`~dsfd.integrations.mqtt.link.Backoff`). Each change of the
broker's state is logged once and saved in ``mqtt_cursor`` (connected, last error, backlog,
delivered, expired) for ``dsfd status``.
"""

from __future__ import annotations

import contextlib
import contextvars
import queue
import threading
import time
from collections import OrderedDict
from datetime import timedelta
from pathlib import Path
from typing import TYPE_CHECKING, Any

from dsfd.config import PanelConfig
from dsfd.daemon.logging_setup import get_logger
from dsfd.integrations.mqtt.connection import Connection
from dsfd.integrations.mqtt.link import Backoff, BrokerLink, new_client, settings_of
from dsfd.integrations.mqtt.messages import (
    daily_kpis,
    discovery_configs,
    dumps,
    finding_messages,
    local_day,
    state_message,
)
from dsfd.integrations.mqtt.outbox import Key, Outbox, Status
from dsfd.integrations.mqtt.receiver import CommandReceiver
from dsfd.storage.findings import open_findings
from dsfd.storage.timeseries import iso_now

if TYPE_CHECKING:
    from paho.mqtt.client import Client

__all__ = ["WINDOW", "MqttPublisher"]

log = get_logger("dsfd.mqtt")

#: State messages in flight (published, PUBACK not yet received) at most.
WINDOW = 100
#: The cursor and the broker state are saved at most this often while messages flow [s].
SAVE_EVERY_S = 2.0
#: How long to wait for the CONNACK after the TCP connection is up [s].
CONNACK_WAIT_S = 10.0
#: At a clean stop, how long the cycles stored so far may take to go out [s].
DRAIN_ON_STOP_S = 2.0


class MqttPublisher:
    """Publishes a panel's stored cycles, availability, KPIs and discovery configs."""

    name = "mqtt"

    def __init__(self, link: BrokerLink, cfg: PanelConfig, *, version: str) -> None:
        mq = settings_of(cfg)
        self.link = link
        self.cfg = cfg
        self.version = version
        self.base = mq.base_topic_for(cfg.panel.id)
        self.discovery_prefix = mq.discovery_prefix
        self.max_age_s = mq.backlog_max_age_h * 3600.0
        self.backoff = Backoff(mq.reconnect_min_s, mq.reconnect_max_s)
        self.destination = f"{link.address} {self.base}"
        self.state_topic = f"{self.base}/state"
        self.availability_topic = f"{self.base}/availability"
        self.error_topic = f"{self.base}/error"
        self.command_filter = f"{self.base}/cmd/#"
        self.receiver = CommandReceiver(cfg, base_topic=self.base, broker=link.address,
                                        answer=self._answer)
        #: The connected client (for the receiver's answers), None while not connected.
        self._live: Client | None = None
        self._wake = threading.Event()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        # Owned by the publisher's thread:
        self.outbox: Outbox | None = None
        self.acked: Key = (0, 0)
        self.acked_time_s: float | None = None
        self.status = Status()
        self._sent: Key = (0, 0)
        self._inflight: OrderedDict[Key, bool] = OrderedDict()
        self._mids: dict[int, tuple[Key, float]] = {}
        self._dirty = False
        self._saved_at = 0.0
        self._kpi_checked: str | None = None
        #: The finding payloads the broker has, by topic (cleared on each connection).
        self._findings_sent: dict[str, str] = {}
        self._failures = 0

    # ------------------------------------------------------------------ the runner's hooks
    def start(self, *, database: Path) -> None:
        """Start the thread (the database exists and is migrated)."""
        ctx = contextvars.copy_context()  # the log lines keep the panel
        self._thread = threading.Thread(target=ctx.run, args=(self._main, database),
                                        name="dsfd-mqtt", daemon=True)
        self._thread.start()
        self.receiver.start(database=database)

    def cycle_stored(self, cycle: int) -> None:
        """A cycle was committed: wake the thread (returns at once)."""
        self._wake.set()

    def stop(self, *, timeout_s: float = 8.0) -> None:
        """Publish ``offline``, disconnect and end the thread (bounded by ``timeout_s``)."""
        self._stop.set()
        self._wake.set()
        if self._thread is not None:
            self._thread.join(timeout_s)
            if self._thread.is_alive():
                log.warning("MQTT publisher did not stop within %g s; abandoned", timeout_s)
        self.receiver.stop()

    # ------------------------------------------------------------------ the thread
    def _main(self, database: Path) -> None:
        try:
            self.outbox = Outbox.open(database, self.destination)
            self.acked, self.status = self.outbox.cursor()
        except Exception:
            log.exception("MQTT publisher cannot read the database; nothing will be published")
            return
        try:
            while not self._stop.is_set():
                conn = self._connect()
                if conn is not None:
                    try:
                        self._serve(conn)
                    except Exception:  # a bug here must not end publishing for good
                        log.exception("MQTT publisher failed; reconnecting")
                    finally:
                        self._close(conn, graceful=self._stop.is_set())
                if self._stop.is_set():
                    break
                self._idle(self.backoff.next_delay())
        finally:
            self._save(force=True)
            self.outbox.close()

    def _idle(self, delay_s: float) -> None:
        """Wait before the next attempt; the backlog (``dsfd status``, the metrics) keeps
        counting the cycles stored meanwhile."""
        deadline = time.monotonic() + delay_s
        while not self._stop.is_set() and (left := deadline - time.monotonic()) > 0:
            if self._wake.wait(min(left, 1.0)):
                self._wake.clear()
                self._dirty = True
                self._save()

    def health(self) -> dict[str, Any]:
        """The broker's state for the metrics file (read from the loop's thread: a snapshot
        of plain values the publisher's threads keep)."""
        st, r = self.status, self.receiver
        return {"connected": st.connected, "last_error": st.last_error,
                "backlog": st.backlog, "delivered": st.delivered,
                "delivered_run": self.acked[0], "delivered_cycle": self.acked[1],
                "delivered_time_s": self.acked_time_s,
                "commands": {"queued": r.queued, "refused": r.refused, "rejected": r.rejected,
                             "dropped": r.dropped}}

    def _connect(self) -> Connection | None:
        client = new_client(self.link)
        client.will_set(self.availability_topic, "offline", qos=1, retain=True)
        client.max_inflight_messages_set(WINDOW)
        client.max_queued_messages_set(WINDOW + 64)  # + availability, discovery, KPIs
        conn = Connection(client, self._wake, self.receiver)
        address = self.link.address
        try:
            client.connect(self.link.host, self.link.port, keepalive=self.link.keepalive_s)
        except (OSError, ValueError) as exc:  # refused, unreachable, DNS, TLS (ssl.SSLError)
            self._failed(f"cannot connect to the MQTT broker {address}: {exc}")
            return None
        client.loop_start()
        deadline = time.monotonic() + CONNACK_WAIT_S
        while not conn.connack.is_set() and not self._stop.is_set():
            if not conn.connack.wait(min(0.2, max(deadline - time.monotonic(), 0.0))) \
                    and time.monotonic() >= deadline:
                break
        if conn.connack.is_set() and not conn.refused and not conn.lost.is_set():
            return conn
        if conn.refused:
            self._failed(f"the MQTT broker {address} refused the connection: {conn.refused}"
                         + (" (check mqtt.username and mqtt.password_file)"
                            if "author" in conn.refused or "password" in conn.refused else ""),
                         level="error")
        elif not self._stop.is_set():
            why = conn.lost_reason or f"no CONNACK within {CONNACK_WAIT_S:g} s"
            self._failed(f"MQTT broker {address} closed the connection: {why}")
        self._close(conn, graceful=False)
        return None

    def _failed(self, message: str, *, level: str = "warning") -> None:
        self._failures += 1
        st = self.status
        if message != st.last_error:
            getattr(log, level)(message + "; control goes on, state is kept for later",
                                broker=self.link.address, attempts=self._failures)
        else:
            log.debug(message, attempts=self._failures)
        st.last_error, st.last_error_utc, st.connected = message, iso_now(), False
        self._save(force=True)

    def _serve(self, conn: Connection) -> None:
        client = conn.client
        self.backoff.reset()
        self.status.connected = True
        self._sent = self.acked
        self._inflight.clear()
        self._mids.clear()
        backlog = self._backlog()
        log.info("MQTT connected", broker=self.link.address, base_topic=self.base,
                 backlog=backlog, after_failures=self._failures or None)
        self._failures = 0
        client.publish(self.availability_topic, "online", qos=1, retain=True)
        # Each connection is a clean session: subscribe again every time.
        client.subscribe(self.command_filter, qos=1)
        self._live = client
        if self.discovery_prefix is not None:
            for topic, config in discovery_configs(self.cfg, base_topic=self.base,
                                                   discovery_prefix=self.discovery_prefix,
                                                   version=self.version):
                client.publish(topic, dumps(config), qos=1, retain=True)
        self._kpi_checked = None
        self._findings_sent = {}
        self._save(force=True)
        while not self._stop.is_set() and not conn.lost.is_set():
            self._wake.wait(0.5)
            self._wake.clear()
            self._take_acks(conn)
            if conn.lost.is_set():
                break
            # One look at the newest stored cycle serves the backlog's age limit and the KPIs.
            newest = self.outbox.newest_time_s() if self.outbox is not None else None
            self._send_more(client, newest_s=newest)
            self._publish_kpi(client, newest)
            self._publish_findings(client)
            self._save()
            self._subscribed(conn)
        if self._stop.is_set() and not conn.lost.is_set():
            self._drain(conn)
        if conn.lost.is_set() and not self._stop.is_set():
            self.status.connected = False
            self._failed(f"MQTT connection to {self.link.address} lost: "
                         f"{conn.lost_reason or 'closed'} ({len(self._inflight)} state "
                         "message(s) unacknowledged, sent again on reconnect)")

    def _subscribed(self, conn: Connection) -> None:
        """Log the broker's answer to the command subscription once per connection."""
        if conn.subscription is None:
            return
        if conn.subscription:
            log.warning("the MQTT broker refused the subscription to %s (%s): commands over "
                        "MQTT do not reach this panel (the broker's ACL?)",
                        self.command_filter, conn.subscription, broker=self.link.address)
        conn.subscription = None

    def _answer(self, text: str) -> None:
        """Publish an answer on ``<base>/error`` (QoS 0, not retained) if connected."""
        client = self._live
        if client is None:
            return
        try:
            client.publish(self.error_topic, text, qos=0, retain=False)
        except (ValueError, RuntimeError, OSError) as exc:
            log.debug("MQTT answer not published: %s", exc)

    def _drain(self, conn: Connection) -> None:
        """At a clean stop: the cycles stored so far go out (bounded by
        :data:`DRAIN_ON_STOP_S`), so the retained state is the last cycle; the rest waits
        in the database for the next start."""
        deadline = time.monotonic() + DRAIN_ON_STOP_S
        while time.monotonic() < deadline and not conn.lost.is_set():
            self._take_acks(conn)
            self._send_more(conn.client)
            if not self._inflight:
                break
            self._wake.wait(0.05)
            self._wake.clear()

    def _send_more(self, client: Client, *, newest_s: float | None = None) -> None:
        import paho.mqtt.client as mqtt

        room = WINDOW - len(self._inflight)
        if room <= 0 or self.outbox is None:
            return
        cycles, skipped, before_first = self.outbox.pending(
            self._sent, limit=room, max_age_s=self.max_age_s, newest_s=newest_s)
        if skipped and before_first is not None:
            self.status.expired += skipped
            log.warning("%d stored cycle(s) older than mqtt.backlog_max_age_h passed over",
                        skipped, backlog_max_age_h=self.max_age_s / 3600.0)
            self._inflight[before_first] = True  # counts as delivered for the cursor
            self._dirty = True
        pid = self.cfg.panel.id
        for p in cycles:
            payload = dumps(state_message(pid, p.row, p.samples, calibrated_s=p.calibrated_s))
            info = client.publish(self.state_topic, payload, qos=1, retain=True)
            if info.rc != mqtt.MQTT_ERR_SUCCESS:
                break  # no connection (the loop notices) or paho's queue is full: later
            self._mids[info.mid] = (p.key, float(p.row["time_s"]))
            self._inflight[p.key] = False
            self._sent = p.key
        self._advance()

    def _take_acks(self, conn: Connection) -> None:
        while True:
            try:
                mid = conn.acks.get_nowait()
            except queue.Empty:
                break
            entry = self._mids.pop(mid, None)
            if entry is None:
                continue  # availability, discovery, KPIs
            key, time_s = entry
            if key in self._inflight:
                self._inflight[key] = True
                self.status.delivered += 1
                if self.acked_time_s is None or time_s > self.acked_time_s:
                    self.acked_time_s = time_s
        self._advance()

    def _advance(self) -> None:
        """Move the cursor over the acknowledged prefix of the in-flight messages."""
        while self._inflight:
            key, done = next(iter(self._inflight.items()))
            if not done:
                break
            self._inflight.popitem(last=False)
            self.acked = max(self.acked, key)
            self._dirty = True

    def _publish_kpi(self, client: Client, newest: float | None) -> None:
        """The last completed local day's KPIs, once per day and once per connection
        (``newest``: the time of the newest stored cycle)."""
        if self.outbox is None or newest is None:
            return
        offset = self.cfg.site.utc_offset_h
        day = local_day(newest, offset) - timedelta(days=1)
        if self._kpi_checked == day.isoformat():
            return
        self._kpi_checked = day.isoformat()
        rows, flagged, updates = self.outbox.day_rows(day, offset)
        if not rows:
            return
        heat, hours = self.outbox.day_heat(day, offset, step_s=self.cfg.model.step_s)
        kpis = daily_kpis(self.cfg.panel.id, day, rows, utc_offset_h=offset,
                          flagged_samples=flagged, calibration_updates=updates,
                          heat_kwh=heat, heat_hours=hours,
                          comfort_rows=self.outbox.day_comfort(day, offset),
                          step_s=self.cfg.model.step_s)
        client.publish(f"{self.base}/kpi", dumps(kpis), qos=1, retain=True)
        self.status.kpi_day = day.isoformat()
        self._dirty = True

    def _publish_findings(self, client: Client) -> None:
        """The open findings per kind (retained), each topic when its payload changed."""
        if self.outbox is None:
            return
        for topic, payload in finding_messages(self.base, open_findings(self.outbox.conn)):
            if self._findings_sent.get(topic) != payload:
                client.publish(topic, payload, qos=1, retain=True)
                self._findings_sent[topic] = payload

    def _backlog(self) -> int:
        if self.outbox is None:
            return 0
        return self.outbox.backlog(self.acked, max_age_s=self.max_age_s)

    def _save(self, *, force: bool = False) -> None:
        now = time.monotonic()
        if self.outbox is None or not (force or (self._dirty
                                                 and now - self._saved_at >= SAVE_EVERY_S)):
            return
        try:
            self.status.backlog = self._backlog()
            self.outbox.save(self.acked, self.status, time_s=self.acked_time_s)
        except Exception as exc:  # the database is busy or full: try again later
            log.warning("MQTT delivery cursor not saved: %s", exc)
            return
        self._dirty = False
        self._saved_at = now

    def _close(self, conn: Connection, *, graceful: bool) -> None:
        client = conn.client
        self._live = None
        if graceful and client.is_connected():
            info = client.publish(self.availability_topic, "offline", qos=1, retain=True)
            with contextlib.suppress(RuntimeError, ValueError):
                info.wait_for_publish(timeout=2.0)
            self._take_acks(conn)
            client.disconnect()
        else:
            client.disconnect()  # stops paho's thread; the will goes out if the link broke
        client.loop_stop()
        self.status.connected = False
