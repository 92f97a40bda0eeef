"""The simulated plant in a child process (dsfd.sim.remote_plant) and the daemon bench on it."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from dsfd.sim.daemon_plant import plant_options, simulated_plant
from dsfd.sim.plant.actuators import CommandError
from dsfd.sim.remote_plant import PlantProcess

PANEL = Path(__file__).resolve().parents[2] / "config" / "panels" / "suwon-south.yaml"


def test_the_plant_in_a_process_reads_what_the_plant_in_process_reads(suwon):
    """Same seed, same calls: the same readings (noise included) and the same heat."""
    kw = {"cfg": suwon, "seed": 4, "cycles": 30, "options": plant_options("lumped")}
    local = simulated_plant(**kw).plant
    commands = [{"phi_deg": 36.0, "afr": 1, "or_pct": 55.0},
                {"phi_deg": -18.0, "afr": 6, "or_pct": 100.0}]
    with PlantProcess(**kw) as remote:
        assert remote.time_s == local.time_s
        for i, cmd in enumerate(commands * 2):
            assert remote.apply(cmd).as_dict() == local.apply(cmd).as_dict()
            local.advance(60.0 * (i + 1))
            assert remote.advance_and_read(remote.time_s + 60.0 * (i + 1)) == \
                local.read_sensors()
            assert remote.time_s == local.time_s
        heat, hours = remote.room_heat()
        assert heat == local.room_heat_j() and hours > 0
        # A command the façade cannot execute is refused with the plant's own error.
        with pytest.raises(CommandError, match="louver grid"):
            remote.apply({"phi_deg": 7.0, "afr": 1, "or_pct": 50.0})
    assert remote.cpu_s > 0 and remote.rss_mb_max > 0


@pytest.mark.slow
def test_the_daemon_bench_measures_a_process_without_the_plant():
    script = (
        "import json, sys\n"
        "from pathlib import Path\n"
        "from dsfd.cli import build_parser\n"
        "build_parser()  # as dsfd bench / dsfd run: the CLI must not load the plant either\n"
        "from dsfd.bench.daemon import bench_daemon\n"
        f"fig = bench_daemon(Path({str(PANEL)!r}), cycles=70, fidelity='lumped')\n"
        "fig['plant_in_daemon'] = float('dsfd.sim.plant.plant' in sys.modules)\n"
        "fig['scipy_in_daemon'] = float(any(m.split('.')[0] == 'scipy' for m in sys.modules))\n"
        "print(json.dumps(fig))\n")
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr
    fig = json.loads(proc.stdout.strip().splitlines()[-1])
    assert fig["plant_in_daemon"] == 0.0
    # calibrated (below) without SciPy: its optimiser is measured, not loaded
    assert fig["scipy_in_daemon"] == 0.0 and fig["import_rss_mb.scipy_optimize"] > 0
    assert fig["cycles"] == 70 and fig["calibration_updates"] >= 1
    groups = [k for k in fig if k.startswith("import_rss_mb.")]
    assert {"import_rss_mb.numpy", "import_rss_mb.scipy_optimize",
            "import_rss_mb.total"} <= set(groups)
    parts = sum(fig[k] for k in groups if k not in (
        "import_rss_mb.total", "import_rss_mb.plant", "import_rss_mb.scipy_optimize"))
    assert parts == pytest.approx(fig["import_rss_mb.total"], rel=1e-9)
    assert 0 < fig["cpu_s_per_cycle"] < 60 and fig["plant_cpu_s_per_cycle"] > 0
    assert fig["rss_mb_max"] >= fig["rss_mb_start"] > fig["import_rss_mb.python"]
    # 4 GB less the OS's 512 MB holds the panels counted, at each one's largest RSS
    panels = fig["panels_per_4gb_2core"]
    assert 1 <= panels <= min(fig["panels_per_4gb_memory"], fig["panels_per_2core_cpu"])
    assert fig["panels_per_4gb_memory"] * fig["rss_mb_max"] <= 4096 - 512
    assert (fig["panels_per_4gb_memory"] + 1) * fig["rss_mb_max"] > 4096 - 512
