"""The simulate progress bar counts output samples (not the oversampled internal records)."""

from pathlib import Path

import tqdm.auto

ROOT = Path(__file__).resolve().parents[2]


def test_progress_bar_counts_output_samples(monkeypatch):
    from fivid.solver import FrictionInput, OperatingCondition, OutputOptions, RunSchedule, simulate

    bars = []

    class Recorder(tqdm.auto.tqdm):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **{**kwargs, "disable": True})
            self.updates = []
            bars.append((kwargs, self))

        def update(self, n=1):
            self.updates.append(n)
            return super().update(n)

    monkeypatch.setattr(tqdm.auto, "tqdm", Recorder)
    ds = simulate(str(ROOT / "configs/models/triboair_coarse.yaml"),
                  OperatingCondition(sliding_velocity=0.01, normal_load=5.0), FrictionInput(mu=0.3),
                  schedule=RunSchedule(duration=1e-3, sample_rate=51200.0),
                  output=OutputOptions(oversample=4, progress=True))
    ((kwargs, bar),) = bars
    assert kwargs["unit"] == "sample"
    assert kwargs["total"] == ds.sizes["time"] == sum(bar.updates)
