"""``bench paper-tables --seeds N``: the per-seed criterion and the progress line each seed
prints when it is done (a run of five seeds takes hours; its JSON comes only at the end).
The protocol itself is replaced by stated figures: this is the bookkeeping, not the physics."""

from __future__ import annotations

import dsfd.bench.paper_tables as pt


def test_every_seed_reports_when_done_and_the_criterion_takes_the_worst(monkeypatch):
    speeds = {0: (0.5, 0.6, 1.1, 1.6), 1: (0.4, 0.5, 0.7, 0.9)}  # regimes 1, 3, 5, 6 [cm/s]

    def fake(cfg, *, seed, weather, validation_days, progress):
        figures = {"truth.f": 26.0 + seed, "online.h1.mean_mae_c": 0.26,
                   "online.h15.mean_mae_c": 0.43}
        figures.update({f"online.velocity_true_mae_cms.regime_{r}": v
                        for r, v in zip((1, 3, 5, 6), speeds[seed], strict=True)})
        return pt.PaperTables(scores=None, figures=figures)

    monkeypatch.setattr(pt, "paper_tables", fake)
    said: list[str] = []
    out = pt.paper_tables_seeds(None, 2, progress=said.append)
    assert said == [
        "seed 0 done: f_true 26, cavity speed vs the true |v| in regimes 1/3/5/6: "
        "0.50/0.60/1.10/1.60 cm/s; T h1 0.2600, h15 0.4300 degC",
        "seed 1 done: f_true 27, cavity speed vs the true |v| in regimes 1/3/5/6: "
        "0.40/0.50/0.70/0.90 cm/s; T h1 0.2600, h15 0.4300 degC"]
    assert out["online_velocity_true_mae_cms_max"] == 1.6
    assert out["criterion.online_velocity_true_le_1cms_every_seed"] == 0.0
    assert out["seed_1.online.velocity_true_mae_cms.regime_6"] == 0.9
