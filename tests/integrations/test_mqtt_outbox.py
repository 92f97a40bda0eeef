"""The database as the publisher's outbox: stored order, the age bound, calibration age, cursor.

A real SQLite store written through :class:`dsfd.storage.timeseries.Store`, as the daemon
writes it; no broker needed.
"""

from __future__ import annotations

from pathlib import Path

from dsfd.integrations.mqtt.outbox import Outbox, Status
from dsfd.storage.timeseries import CycleRecord, Store

T0 = 1_641_000_000.0
THETA = {"h_out": 20.0, "f": 100.0}


def _record(cycle: int, time_s: float, *, online: bool = False) -> CycleRecord:
    decision = {"slot": cycle - 1, "time_s": time_s, "time_utc": "t", "method": "mpc",
                "phi_deg": 0.0, "afr": 10, "or_pct": 0.0, "write_status": "dry-run",
                "cycle_ms": 10.0}
    return CycleRecord(cycle=cycle, time_s=time_s, decision=decision,
                       samples=[("x1_c", 10.0 + cycle, "good", ""),
                                ("x2_c", None, "timeout", "late")],
                       parameters=("online", THETA, 1.0, "") if online else None)


def _store(path: Path) -> Path:
    store = Store.open(path)
    store.begin_run(panel="p", mode="test", version="0", config_path=None)
    for k in range(1, 11):  # run 1: cycles 1..10 every 60 s, updates at 3 and 7
        store.append(_record(k, T0 + 60 * k, online=k in (3, 7)))
    store.end_run(reason="test", cycles=10)
    store.begin_run(panel="p", mode="test", version="0", config_path=None)
    for k in range(1, 6):  # run 2 continues the clock
        store.append(_record(k, T0 + 600 + 60 * k))
    store.close()
    return path / "timeseries.sqlite"


def test_pending_cycles_come_in_stored_order_with_their_calibration_time(tmp_path):
    outbox = Outbox.open(_store(tmp_path), "broker base")
    cycles, skipped, before = outbox.pending((0, 0), limit=100, max_age_s=1e9)
    assert [c.key for c in cycles] == [(1, k) for k in range(1, 11)] + [(2, k)
                                                                       for k in range(1, 6)]
    assert skipped == 0 and before is None
    cal = {c.key: c.calibrated_s for c in cycles}
    assert cal[(1, 2)] is None and cal[(1, 3)] == cal[(1, 6)] == T0 + 180
    assert cal[(1, 7)] == cal[(2, 5)] == T0 + 420
    first = cycles[0]
    assert first.samples == {"x1_c": (11.0, "good"), "x2_c": (None, "timeout")}
    assert first.row["mode"] == "test"
    assert [c.key for c in outbox.pending((1, 8), limit=3, max_age_s=1e9)[0]] == [
        (1, 9), (1, 10), (2, 1)]


def test_cycles_older_than_the_age_bound_are_passed_over_and_counted(tmp_path):
    outbox = Outbox.open(_store(tmp_path), "broker base")
    # Newest cycle at T0 + 900 s; 330 s back keeps run 1's cycle 10 (T0 + 600) and run 2.
    cycles, skipped, before = outbox.pending((0, 0), limit=3, max_age_s=330.0)
    assert [c.key for c in cycles] == [(1, 10), (2, 1), (2, 2)]
    assert skipped == 9 and before == (1, 9)
    assert outbox.backlog((0, 0), max_age_s=330.0) == 6
    assert outbox.backlog((2, 2), max_age_s=330.0) == 3


def test_the_cursor_and_the_broker_state_survive_a_reopen(tmp_path):
    db = _store(tmp_path)
    outbox = Outbox.open(db, "broker base")
    assert outbox.cursor() == ((0, 0), Status())
    outbox.save((2, 3), Status(connected=True, last_error="lost", backlog=2, delivered=13,
                               expired=1, kpi_day="2022-01-01"), time_s=T0 + 780)
    outbox.close()
    again = Outbox.open(db, "broker base")
    key, status = again.cursor()
    assert key == (2, 3) and (status.delivered, status.expired) == (13, 1)
    assert status.kpi_day == "2022-01-01"
    assert Outbox.open(db, "other broker").cursor()[0] == (0, 0)  # one cursor per destination
