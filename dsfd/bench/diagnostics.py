"""``dsfd bench diagnostics``: does the running daemon find each simulated fault, in time, by
its right name, and nothing on a clean façade? (issue 38, docs/model.md#diagnostics-bench)

Every scenario is one real ``dsfd run --dry-run --plant sim`` (a subprocess: the daemon's
own loop, calibration and findings thread, on the full truth plant) with at most one
``--fault``; the bench reads the ``findings`` table it leaves and scores it
(:mod:`dsfd.bench.diagnostics_table`: the faults, their names, false findings, delays).

The residual detector needs six days of history and the night check eight
([findings](#findings)), so those faults start after a clean prefix of
:data:`~dsfd.bench.diagnostics_table.PREFIX_DAYS`; the stuck damper starts 30 min into a
morning. Cooling weather is the bundled winter record with the outdoor air shifted by
+25 K and the room at 25 °C in cooling mode (as the closed-loop bench's cooling cases).
A simulated day of the daemon costs about 4 CPU minutes on a 2-core machine, so the
scenarios run one after another and ``on_figures`` gets the figures after each;
:func:`recheck` scores kept runs again with today's detectors without running them.
"""

from __future__ import annotations

import signal
import sqlite3
import subprocess
import sys
import tempfile
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import IO

import numpy as np
import yaml

from dsfd.bench.diagnostics_table import (
    NAMES,
    PREFIX_DAYS,
    SECONDS_PER_DAY,
    Scenario,
    scenarios,
    score,
)

__all__ = ["NAMES", "PREFIX_DAYS", "SEASONS", "Scenario", "aalborg_findings",
           "bench_diagnostics", "recheck", "report", "scenarios", "score"]

SEASONS = ("winter", "cooling")
COOLING_T_OUT_OFFSET_K = 25.0
COOLING_ROOM_C = 25.0


# ------------------------------------------------------------------------------- running
def _cooling_inputs(config: Path, work: Path) -> tuple[Path, str]:
    """The panel in cooling mode with the room at 25 °C, and the bundled winter record with
    its outdoor air shifted by +25 K (the closed-loop bench's cooling cases)."""
    import csv

    from dsfd.sim.daemon_plant import DEFAULT_WEATHER
    from dsfd.weather.readers import bundled_weather

    doc = yaml.safe_load(config.read_text()) or {}
    doc.setdefault("control", {})["mode"] = "cooling"
    doc.setdefault("room", {})["t_in_c"] = COOLING_ROOM_C
    panel = work / "panel-cooling.yaml"
    panel.write_text(yaml.safe_dump(doc, sort_keys=False))
    with bundled_weather(DEFAULT_WEATHER).open(newline="") as src:
        rows = list(csv.reader(src))
    col = rows[0].index("Ambient Temperature")
    for row in rows[1:]:
        if len(row) > col and row[col].strip():
            row[col] = repr(float(row[col]) + COOLING_T_OUT_OFFSET_K)
    weather = work / "rmis-golden-2022-01-plus25K.csv"
    with weather.open("w", newline="") as dst:
        csv.writer(dst).writerows(rows)
    return panel, str(weather)


def _run(config: Path, scenario: Scenario, *, seed: int, weather: str | None, state: Path
         ) -> Path:
    """One real ``dsfd run`` of the scenario; its database. Its log is ``state``/run.log."""
    from dsfd.config import load_panel

    period_s = load_panel(config).daemon.cycle_period_s
    args = [sys.executable, "-m", "dsfd", "run", "--config", str(config), "--dry-run",
            "--plant", "sim", "--seed", str(seed), "--state-dir", str(state),
            "--cycles", str(round(scenario.days * SECONDS_PER_DAY / period_s)),
            "--log-format", "json"]
    args += ["--weather", weather] if weather else []
    args += ["--start", scenario.start] if scenario.start else []
    args += ["--fault", scenario.fault] if scenario.fault else []
    state.mkdir(parents=True, exist_ok=True)
    log = state / "run.log"
    with log.open("w") as out:
        rc = _run_child(args, out)
    if rc != 0:
        raise RuntimeError(f"dsfd run for {scenario.name} (seed {seed}) exited {rc}; "
                           f"its log: {log}")
    return state / "timeseries.sqlite"


def _run_child(args: list[str], out: IO[str]) -> int:
    """Run ``args`` to its end; its exit code. A SIGTERM to the bench (or Ctrl-C) is passed
    on to the run, which stops after its cycle, and then stops the bench: a stopped bench
    leaves no daemon behind."""
    child = subprocess.Popen(args, stdout=out, stderr=subprocess.STDOUT)
    stopped = False

    def stop(_signum: int, _frame: object) -> None:
        nonlocal stopped
        stopped = True
        child.terminate()

    previous = signal.signal(signal.SIGTERM, stop)
    try:
        rc = child.wait()
    except KeyboardInterrupt:
        stopped = True
        child.terminate()
        rc = child.wait()
    finally:
        signal.signal(signal.SIGTERM, previous)
    if stopped:
        raise KeyboardInterrupt(f"stopped; the run ended with exit code {rc}")
    return rc


def bench_diagnostics(config: Path, *, seeds: Sequence[int], seasons: Sequence[str] = SEASONS,
                      names: Iterable[str] | None = None, clean_days: float = 10.0,
                      keep: Path | None = None, aalborg: Path | None = None,
                      rechecked: Path | None = None,
                      aalborg_panel: Path | None = None,
                      progress: Callable[[str], None] | None = None,
                      on_figures: Callable[[dict[str, float | str]], None] | None = None
                      ) -> dict[str, float | str]:
    """Run the scenarios (:func:`scenarios`, those in ``names``) for every season and seed,
    one after another; flat figures ``<season>.<scenario>.seed<N>.<figure>``, handed to
    ``on_figures`` after each run. ``keep``: keep each run's state directory there.
    ``rechecked``: instead of running, score the runs an earlier ``keep`` left there again
    with today's detectors (:func:`recheck`; runs it does not hold are skipped).
    ``aalborg``: the Aalborg "Cube" source folder, scored first (:func:`aalborg_findings`,
    with ``aalborg_panel``, by default ``aalborg-cube.yaml`` beside ``config``)."""
    unknown = sorted(set(seasons) - set(SEASONS))
    if unknown:
        raise ValueError(f"unknown season(s) {', '.join(unknown)}; choose from "
                         f"{', '.join(SEASONS)}")
    table = scenarios(clean_days=clean_days)
    chosen = set(names) if names is not None else {s.name for s in table}
    if unknown := sorted(chosen - {s.name for s in table}):
        raise ValueError(f"unknown scenario(s) {', '.join(unknown)}; choose from "
                         f"{', '.join(s.name for s in table)}")
    plan = [s for s in table if s.name in chosen]
    figures: dict[str, float | str] = {"seeds": ",".join(map(str, seeds)),
                                       "seasons": ",".join(seasons)}
    if aalborg is not None:
        if progress:
            progress(f"aalborg: replaying {aalborg} with the self-calibrating model")
        figures.update(aalborg_findings(aalborg_panel or config.parent / "aalborg-cube.yaml",
                                        aalborg))
        if on_figures:
            on_figures(dict(figures))
    replayed = 0
    missing: list[str] = []
    with tempfile.TemporaryDirectory(prefix="dsfd-bench-diag-") as tmp:
        root = keep or Path(tmp)
        root.mkdir(parents=True, exist_ok=True)
        inputs: dict[str, tuple[Path, str | None]] = {"winter": (config, None)}
        if "cooling" in seasons:
            inputs["cooling"] = _cooling_inputs(config, root)
        for season in seasons:
            panel, weather = inputs[season]
            for seed in seeds:
                for scenario in plan:
                    key = f"{season}.{scenario.name}.seed{seed}"
                    if rechecked is not None:
                        if not (rechecked / key / "timeseries.sqlite").exists():
                            missing.append(key)
                            continue  # not kept: that run was not made
                        if progress:
                            progress(f"{key}: replaying the detectors over {rechecked / key}")
                        fig = recheck(rechecked / key, scenario, panel, root / key)
                        replayed += 1
                    else:
                        if progress:
                            progress(f"{key}: {scenario.days:g} simulated days, fault "
                                     f"{scenario.fault or 'none'}")
                        fig = score(_run(panel, scenario, seed=seed, weather=weather,
                                         state=root / key), scenario)
                    figures.update({f"{key}.{k}": v for k, v in fig.items()})
                    if on_figures:
                        on_figures(dict(figures))
    if rechecked is not None and not replayed:
        raise ValueError(f"--recheck {rechecked}: no kept run of these seasons, scenarios and "
                         f"seeds there (looked for {', '.join(missing)}; a run is a "
                         "<season>.<scenario>.seed<N> folder with its timeseries.sqlite, as "
                         "--keep-state leaves it)")
    return figures


def recheck(state: Path, scenario: Scenario, panel: Path, work: Path
            ) -> dict[str, float | str]:
    """Score a kept run again with today's detectors: its database is copied (SQLite's
    backup, migrated to the current schema), its findings dropped, and the daemon's checks
    replayed over the stored rows every :data:`~dsfd.daemon.findings.CHECK_EVERY_S`. The
    detectors never act on the façade, so a replay sees what the running daemon would have
    seen; the costly part of the bench, the runs, need not be repeated to try a detector."""
    from dsfd.config import load_panel
    from dsfd.daemon.findings import CHECK_EVERY_S, FindingsStage, NightSite
    from dsfd.storage.schema import connect_checked

    cfg = load_panel(panel)
    work.mkdir(parents=True, exist_ok=True)
    db = work / "timeseries.sqlite"
    src = sqlite3.connect(f"file:{state / 'timeseries.sqlite'}?mode=ro", uri=True)
    dst = sqlite3.connect(db)
    try:
        src.backup(dst)
    finally:
        src.close()
        dst.close()
    connect_checked(db).close()
    conn = sqlite3.connect(db)
    try:
        conn.execute("DELETE FROM findings")
        conn.commit()
        t0, t1 = (float(v) for v in conn.execute(
            "SELECT MIN(time_s), MAX(time_s) FROM decisions").fetchone())
        stage = FindingsStage(db, run_id=lambda: None, panel=cfg, night=NightSite.of(cfg))
        for now in np.arange(t0 + CHECK_EVERY_S, t1 + 1.0, CHECK_EVERY_S):
            stage.check(conn, float(now))
    finally:
        conn.close()
    return score(db, scenario)


def aalborg_findings(panel: Path, source_dir: Path) -> dict[str, float | str]:
    """False findings of the residual detector and the night offsets on the real Aalborg
    "Cube" week.

    The record (``dsfd convert-aalborg``) is replayed with the self-calibrating model as
    ``dsfd validate`` does; the residual detector with the daemon's settings runs on the
    one-step prediction errors of each measured pane over the whole week, and the night
    offsets on the replay's heat-flux offsets at the panel's nights (the daemon's last
    check of such a week sees the same rows; each detector reports its first change
    anywhere in them). The record has no cavity speed and a week of nights is too short
    for the night check, so the other detectors have nothing to judge. Every finding is
    false: the façade did not change during the measurements.
    """
    from dsfd.config import load_panel
    from dsfd.convert.aalborg import convert_aalborg
    from dsfd.estimation.diagnostics import residual_change, residual_settings
    from dsfd.estimation.night_offsets import NIGHT_OFFSET_NAMES, night_offset_change
    from dsfd.estimation.stepdata import step_data
    from dsfd.estimation.validation import replay_scores
    from dsfd.storage.evidence import night_mask

    cfg = load_panel(panel)
    steps = step_data(cfg, convert_aalborg(source_dir))
    replay = replay_scores(cfg, steps, horizons=(1,))
    t = replay.one_step_time_s
    found = [f for name, err in replay.one_step_error_k.items()
             if (f := residual_change(t, err, signal=f"{name}_c", unit="K",
                                      settings=residual_settings("K"))) is not None]
    t_steps = steps.time_s[:-1]
    night = night_mask(t_steps, latitude_deg=cfg.site.latitude_deg,
                       longitude_deg=cfg.site.longitude_deg)
    found += [f for name in NIGHT_OFFSET_NAMES
              if name in replay.online_offsets_wm2
              and (f := night_offset_change(t_steps, replay.online_offsets_wm2[name], night,
                                            name=name)) is not None]
    return {"aalborg.days": float((t[-1] - t[0]) / SECONDS_PER_DAY) if t.size else 0.0,
            "aalborg.outputs": ",".join(replay.one_step_error_k),
            "aalborg.false_findings": float(len(found)),
            "aalborg.false_kinds": ",".join(f"{f.kind}:{f.evidence[0].signal}"
                                            for f in found)}


def report(figures: dict[str, float | str]) -> str:
    """The table of the issue's targets and the false findings, one row per run."""
    head = (f"{'season':8} {'scenario':13} {'seed':>4}  {'first finding':28} {'named':5} "
            f"{'delay':>8} {'target':>8} {'unit':13} {'false':>5} {'clean d':>7}")
    lines = [head, "-" * len(head)]
    runs = sorted({k.rsplit(".", 1)[0] for k in figures if k.count(".") >= 3},
                  key=lambda k: (k.split(".")[0], _order(k.split(".")[1]), k))
    total_days = total_false = 0.0
    for key in runs:
        season, name, seed = key.split(".")
        f = {k.rsplit(".", 1)[1]: v for k, v in figures.items() if k.startswith(key + ".")}
        total_days += float(f.get("clean_days", 0.0))
        total_false += float(f.get("false_findings", 0.0))
        unit = next(s.delay_unit for s in scenarios(clean_days=1.0) if s.name == name)
        if name == "clean":
            first, named, delay, target = "", "", "", ""
        else:
            first = str(f.get("first_kind") or "none")
            named = "yes" if f.get("named") else "no"
            delay = f"{float(f['name_delay_min']):.0f}" if "name_delay_min" in f else (
                f">{float(f.get('observed_min', 0.0)):.0f}")
            target = f"{float(f.get('deadline_min', 0.0)):.0f}"
        lines.append(f"{season:8} {name:13} {seed[4:]:>4}  {first[:28]:28} {named:5} "
                     f"{delay:>8} {target:>8} {unit if name != 'clean' else '':13} "
                     f"{float(f.get('false_findings', 0.0)):5.0f} "
                     f"{float(f.get('clean_days', 0.0)):7.2f}")
    lines.append(f"false findings: {total_false:.0f} over {total_days:.2f} clean simulated days")
    if "aalborg.false_findings" in figures:
        lines.append(f"Aalborg Cube (real; residual detector on {figures['aalborg.outputs']}, "
                     "night offsets on q_x2..q_x4): "
                     f"{float(figures['aalborg.false_findings']):.0f} false findings over "
                     f"{float(figures['aalborg.days']):.1f} days"
                     + (f" ({figures['aalborg.false_kinds']})"
                        if figures["aalborg.false_kinds"] else ""))
    return "\n".join(lines)


def _order(name: str) -> int:
    return [s.name for s in scenarios(clean_days=1.0)].index(name) if name in NAMES or \
        name == "clean" else 99
