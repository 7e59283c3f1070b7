"""The estimators on a REAL friction-force signal: the banded rotary friction damper of
../shared/real_data/friction_damper (Coble, Huggins, Cao, Ricles, Downey, 2022, CC BY-SA 4.0).

Not the physics of the TRIBOAIR rig and no law is claimed: the damper is driven by a 1 Hz sinusoidal
displacement, so there is no steady sliding. What the data can check:
- every run is excluded with the reason "not in steady sliding" (the velocity has no plateau);
- the slip force (mean friction force while the velocity is above half its peak) with its batch-means
  interval grows with the band tension that sets it (20 lb < 35 lb), intervals well apart;
- the mains-line detector raises no false alarm at the 60 Hz harmonics (US mains) of the force PSD,
  where the data show no lines (PSD at 60-240 Hz within a factor 1.6 of the neighbouring median).
"""

import json

import numpy as np
import pytest
import xarray as xr

from fivid.errors import DataQualityError
from fivid.identify import identify_friction_law
from fivid.identify.runs import batch_means_interval, mains_line_bins
from fivid.schema import apply_cf_attrs, new_history
from fivid.signal import welch_psd
from fivid.units import convert

FILES = {"1Hz20lbtension.json": 20.0, "1Hz35lbtension.json": 35.0, "1Hz80lbtension.json": 80.0}


def damper_run(path, tension_lbf):
    """RunDataset of a damper file: friction force [N], encoder velocity [m s-1], acceleration from the
    displacement (second differences) [m s-2]; normal force = the band tension [N], a stand-in."""
    d = json.loads(path.read_text())
    a = np.asarray(d["data"], float)
    t = a[:, 0]
    x = convert(a[:, 1], "in", "m")
    fs = float(d["sampling freq"])
    ds = xr.Dataset(
        {
            "friction_force": ("time", convert(a[:, 2], "kip", "N")),
            "velocity": ("time", convert(a[:, 3], "in/s", "m s-1")),
            "position": ("time", x),
            "acceleration": ("time", np.gradient(np.gradient(x, t), t)),
            "normal_force": ("time", np.full(t.size, convert(tension_lbf, "lbf", "N"))),
        },
        coords={"time": t},
        attrs={"run_id": path.stem, "rig": "friction damper (ARTS-Lab)", "sliding_velocity": 0.0254 * 6.4,
               "normal_load": convert(tension_lbf, "lbf", "N"), "roughness_ra": 1e-6, "sample_rate": fs,
               "source": f"{path.name} (CC BY-SA 4.0, Coble et al. 2022)", "history": new_history("test")},
    )
    return apply_cf_attrs(ds)


@pytest.fixture(scope="module")
def runs(request):
    from pathlib import Path

    folder = Path(__file__).resolve().parents[2].parent / "shared" / "real_data" / "friction_damper"
    if not folder.is_dir():
        pytest.skip("../shared/real_data/friction_damper is not beside the repository")
    return [damper_run(folder / name, tension) for name, tension in FILES.items()]


def test_sinusoidal_motion_is_not_steady_sliding(runs):
    with pytest.raises(DataQualityError, match="no usable run among 3") as info:
        identify_friction_law(runs, band=(10.0, 200.0), mains_frequency=60.0)
    assert str(info.value).count("not in steady sliding") == 3


def test_slip_force_grows_with_band_tension(runs):
    levels = []
    for ds in runs:
        v = ds["velocity"].values
        f = ds["friction_force"].values
        slip = v > 0.5 * v.max()
        levels.append(batch_means_interval(f[slip], 10, 0.95))
    (m20, ci20), (m35, ci35) = levels[0], levels[1]
    assert ci20[1] < ci35[0], levels  # 20 lb: ~4.3 kN, 35 lb: ~9.8 kN
    assert all(m > 0 for m, _ in levels)


def test_no_false_mains_lines_on_the_real_force_psd(runs):
    for ds in runs:
        da = ds["friction_force"] - ds["friction_force"].mean()
        da = da.assign_attrs(units="N")
        p = welch_psd(da.rename("friction_force"), nperseg=1024)
        mask = mains_line_bins(p["frequency"].values, p.values, p.attrs["equivalent_degrees_of_freedom"], 60.0,
                               (10.0, 400.0))
        assert not mask.any(), ds.attrs["run_id"]
