"""What ``dsfd run`` checks and resolves before it opens anything: the run-time checks of the
configuration (key paths as in the YAML file) and the state directory."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING

from dsfd.config import ConfigError, ConfigIssue, PanelConfig, load_panel
from dsfd.config.devices import Devices
from dsfd.daemon.metrics import metrics_problem
from dsfd.signals import ACTUATOR_NAMES

if TYPE_CHECKING:
    from dsfd.daemon.runner import RunOptions

__all__ = ["configured_state_dir", "load_for_run", "resolve_state_dir", "runtime_problems"]

#: Read and write budgets of a panel without a devices: section (the simulated plant): the
#: defaults of the devices: section.
DEFAULT_READ_BUDGET_S: float = Devices.__dataclass_fields__["read_budget_s"].default
DEFAULT_WRITE_BUDGET_S: float = Devices.__dataclass_fields__["write_budget_s"].default


def runtime_problems(cfg: PanelConfig, *, simulated_plant: bool, dry_run: bool
                     ) -> list[ConfigIssue]:
    """Checks that only ``dsfd run`` needs (key paths as in the YAML file)."""
    out: list[ConfigIssue] = []
    d = cfg.daemon
    if abs(d.cycle_period_s - cfg.model.step_s) > 1e-9:
        out.append(ConfigIssue("daemon.cycle_period_s", d.cycle_period_s,
                               f"must equal model.step_s ({cfg.model.step_s:g} s): the "
                               "observer and the calibrator predict one model step per cycle"))
    dev = cfg.devices
    read_s = dev.read_budget_s if dev else DEFAULT_READ_BUDGET_S
    write_s = dev.write_budget_s if dev else DEFAULT_WRITE_BUDGET_S
    parts = {"devices.read_budget_s": read_s, "daemon.calibrate_budget_s": d.calibrate_budget_s,
             "control.time_budget_s": cfg.control.time_budget_s,
             "devices.write_budget_s": write_s, "daemon.store_budget_s": d.store_budget_s}
    if sum(parts.values()) > d.cycle_period_s:
        shown = " + ".join(f"{k} {v:g}" for k, v in parts.items())
        out.append(ConfigIssue("daemon.cycle_period_s", d.cycle_period_s,
                               f"the stage budgets do not fit into one cycle ({shown} = "
                               f"{sum(parts.values()):g} s)"))
    metrics = metrics_problem(d.metrics_file)
    if metrics:
        out.append(ConfigIssue("daemon.metrics_file", d.metrics_file, metrics))
    if simulated_plant:
        return out
    if dev is None:
        out.append(ConfigIssue("devices", None, "required to run against hardware: describe "
                               "the Modbus devices and the weather station (or use --plant "
                               "sim for a simulated plant)"))
        return out
    delivered = dev.sensor_signals()
    for i, name in enumerate(cfg.safety.fault_signals):
        if name not in delivered:
            out.append(ConfigIssue(f"safety.fault_signals[{i}]", name,
                                   "no device in devices.entries delivers this sensor, so the "
                                   "daemon would only ever command the safe state"))
    owned = {a.signal for e in dev.entries for a in e.actuators}
    missing = [a for a in ACTUATOR_NAMES if a not in owned]
    if missing and not dry_run:
        out.append(ConfigIssue("devices.entries", [e.name for e in dev.entries],
                               f"no device has a register for {', '.join(missing)}: the "
                               "daemon cannot command the panel (or use --dry-run)"))
    return out


def load_for_run(path: Path, *, simulated_plant: bool, dry_run: bool) -> PanelConfig:
    """Load and validate a panel file for ``dsfd run``; :class:`ConfigError` names key paths."""
    cfg = load_panel(path)
    issues = runtime_problems(cfg, simulated_plant=simulated_plant, dry_run=dry_run)
    if issues:
        raise ConfigError(issues, str(path))
    return cfg


def configured_state_dir(cfg: PanelConfig) -> Path | None:
    """The panel's ``daemon.state_directory``, else systemd's ``$STATE_DIRECTORY``, else None."""
    if cfg.daemon.state_directory:
        return Path(cfg.daemon.state_directory)
    env = os.environ.get("STATE_DIRECTORY", "")
    if env:
        return Path(env.split(":")[0])  # systemd lists several, colon-separated
    return None


def resolve_state_dir(opts: RunOptions, cfg: PanelConfig) -> tuple[Path, bool]:
    """The state directory and whether it is a temporary one (simulated dry runs only)."""
    if opts.state_dir is not None:
        return opts.state_dir, False
    configured = configured_state_dir(cfg)
    if configured is not None:
        return configured, False
    if opts.simulated_plant:
        return Path(tempfile.mkdtemp(prefix=f"dsfd-{cfg.panel.id}-")), True
    raise ConfigError([ConfigIssue(
        "daemon.state_directory", None, "no state directory: set it here, pass --state-dir, "
        "or run under systemd with StateDirectory= (sets $STATE_DIRECTORY)")],
        str(opts.config_path))
