"""Plausibility of ingested rig data (issue 18 B): errors where the data cannot be right, warnings in the
dataset's quality report otherwise; each names the file, the variable or key, the value and the range."""

import logging

import numpy as np
import pytest
from tests.helpers.ingest import GOOD_META, N_META_LINES, data_line, rig_rows, with_field, write_rig

from fivid.errors import DataQualityError
from fivid.io import read_rig_csv
from fivid.io.plausibility import CLIP_RUN, MAX_FORCE

FN, FT, ACC = 3, 2, 1  # field indices of normal_force, friction_force, acceleration in rig_rows()


def _rows(n=400, **fields):
    rows = rig_rows(n)
    for index, fn in fields.items():
        rows = [with_field(r, {"fn": FN, "ft": FT, "acc": ACC}[index], fn(i, r)) for i, r in enumerate(rows)]
    return rows


def _reject(tmp_path, **kw) -> DataQualityError:
    path = write_rig(tmp_path / "run.csv", **kw)
    with pytest.raises(DataQualityError) as info:
        read_rig_csv(path)
    assert info.value.file == str(path)
    return info.value


def _report(tmp_path, caplog, **kw) -> str:
    path = write_rig(tmp_path / "run.csv", **kw)
    with caplog.at_level(logging.WARNING, logger="fivid"):
        ds = read_rig_csv(path)
    return ds.attrs["quality_report"]


def test_plausible_rows_pass(tmp_path, caplog):
    report = _report(tmp_path, caplog)
    assert report.startswith("plausibility") and "passed" in report
    assert not caplog.records


@pytest.mark.parametrize("name", ["R001_v10_ra08.csv"])
def test_shipped_sample_is_plausible(root, name, caplog):
    with caplog.at_level(logging.WARNING, logger="fivid"):
        ds = read_rig_csv(root / "sample_data" / name)
    assert "passed" in ds.attrs["quality_report"] and not caplog.records


def test_shipped_twin_is_plausible(root, caplog):
    with caplog.at_level(logging.WARNING, logger="fivid"):
        for path in sorted((root / "sample_data" / "twin").glob("*.csv")):
            assert "passed" in read_rig_csv(path).attrs["quality_report"]
    assert not caplog.records


def test_absurd_force_is_an_error(tmp_path):
    rows = _rows(ft=lambda i, r: "1e30" if i == 7 else r.split(",")[FT])
    err = _reject(tmp_path, rows=rows)
    assert err.column == "friction_force" and err.line == data_line(7)
    assert "1e+30 N" in err.message and f"{MAX_FORCE:g} N" in err.message


def test_absurd_acceleration_is_an_error(tmp_path):
    rows = _rows(acc=lambda i, r: "2e5" if i == 3 else r.split(",")[ACC])  # 2e5 g = 2e6 m s-2
    err = _reject(tmp_path, rows=rows)
    assert err.column == "acceleration" and "m s-2" in err.message


@pytest.mark.parametrize("ra", ["0 um", "-0.8 um"])
def test_roughness_not_positive_is_an_error(tmp_path, ra):
    err = _reject(tmp_path, meta={**GOOD_META, "roughness_ra": ra})
    assert err.key == "roughness_ra" and err.line == 1 + list(GOOD_META).index("roughness_ra") + 1
    assert "> 0" in err.message


def test_negative_normal_load_header_is_an_error(tmp_path):
    err = _reject(tmp_path, meta={**GOOD_META, "normal_load": "-5 N"})
    assert err.key == "normal_load" and "-5 N" in err.message


def test_reversed_normal_force_sign_is_an_error(tmp_path):
    rows = _rows(fn=lambda i, r: "-" + r.split(",")[FN])
    err = _reject(tmp_path, rows=rows)
    assert err.column == "normal_force" and "sign" in err.message and "+5 N" in err.message


def test_load_mismatch_is_a_warning(tmp_path, caplog):
    report = _report(tmp_path, caplog, meta={**GOOD_META, "normal_load": "50 N"})
    assert "warning: normal_force:" in report and "50 N" in report and "20%" in report
    assert any("normal_force" in r.getMessage() for r in caplog.records)


def test_friction_coefficient_outside_range_is_a_warning(tmp_path, caplog):
    rows = _rows(ft=lambda i, r: f"{15.0 + 0.01 * (i % 3):.4f}")  # mu = 3
    report = _report(tmp_path, caplog, rows=rows)
    assert "warning: friction_force:" in report and "[0, 2]" in report and "Ft/Fn = 2.9" in report


def test_clipped_acceleration_is_a_warning(tmp_path, caplog):
    top = "0.5000"
    rows = _rows(acc=lambda i, r: top if 100 <= i < 100 + CLIP_RUN + 2 else r.split(",")[ACC])
    report = _report(tmp_path, caplog, rows=rows)
    assert "warning: acceleration:" in report and "clipped" in report and "maximum" in report


def test_single_peak_is_not_clipping(tmp_path, caplog):
    rows = _rows(acc=lambda i, r: "0.5000" if i == 100 else r.split(",")[ACC])
    assert "passed" in _report(tmp_path, caplog, rows=rows)


def test_velocity_mismatch_is_a_warning(tmp_path, caplog):
    header = "time [s],acceleration [g],friction_force [N],normal_force [N],position [mm],velocity [mm/s]"
    rows = [r + ",1.0" for r in rig_rows(100)]  # 1 mm/s measured, 10 mm/s in the header
    report = _report(tmp_path, caplog, rows=rows, header=header)
    assert "warning: velocity:" in report and "-90 %" in report


def test_time_in_ms_labelled_s_without_a_stated_rate(tmp_path):
    """Issue 32 item 4: no sample_rate line; the stamps' spacing (19.5 Hz) is outside the DAQ range while 1000x
    it (19.5 kHz) is inside, so the run is refused with the advice the stated-rate case gives."""
    rows = [with_field(r, 0, f"{i * 1e-3 * 51.2:.9f}") for i, r in enumerate(rig_rows(100))]  # ms under 's'
    err = _reject(tmp_path, rows=rows)
    assert err.column == "time" and err.line == data_line(0)
    assert "19.5312 Hz" in err.message and "[1 kHz, 10 MHz]" in err.message
    stated = _reject(tmp_path, rows=[with_field(r, 0, f"{1e3 * i / 51200:.9f}") for i, r in enumerate(rig_rows(100))],
                     extra_meta=["# sample_rate: 51.2 kHz"])
    hint = stated.message[stated.message.index("the ratio is"):]
    assert hint in err.message  # the header case's message, word for word


def test_time_in_ms_labelled_s_can_be_allowed(tmp_path, caplog):
    rows = [with_field(r, 0, f"{i * 1e-3 * 51.2:.9f}") for i, r in enumerate(rig_rows(100))]
    path = write_rig(tmp_path / "run.csv", rows=rows)
    with caplog.at_level(logging.WARNING, logger="fivid"):
        ds = read_rig_csv(path, allow_implausible=True)
    assert ds.attrs["allow_implausible"] == "yes"
    assert ds.attrs["quality_report"].startswith("allowed (--allow-implausible): time: ")
    assert ds.attrs["sample_rate"] == pytest.approx(1 / 0.0512, rel=1e-6)  # kept as the stamps give it


def test_rate_no_factor_explains_stays_a_warning(tmp_path, caplog):
    """5e-4 Hz: neither 1e3 nor 1e6 times it is a DAQ rate, so it is only the low-rate warning."""
    rows = [with_field(r, 0, f"{i * 2000.0:.1f}") for i, r in enumerate(rig_rows(100))]
    report = _report(tmp_path, caplog, rows=rows)
    assert "warning: sample_rate:" in report and "below 1000 Hz" in report


@pytest.mark.parametrize("rate", ["0 Hz", "1e-320 Hz", "-51.2 kHz"])
def test_stated_rate_that_is_no_rate(tmp_path, rate):
    """sample_rate 0 Hz was a ZeroDivisionError (issue 32); 1e-320 Hz (denormal) too."""
    err = _reject(tmp_path, extra_meta=[f"# sample_rate: {rate}"])
    assert err.key == "sample_rate" and err.line == N_META_LINES + 1
    if rate != "1e-320 Hz":
        assert "> 0" in err.message
    else:
        assert "does not match the time column" in err.message


@pytest.mark.parametrize("load", ["5 kN", "5 mN"])
def test_thousandfold_load_gap_is_an_error(tmp_path, load):
    """Measured 5 N against a nominal 5 kN (or 5 mN): a unit error, not a rig (issue 32)."""
    err = _reject(tmp_path, meta={**GOOD_META, "normal_load": load})
    assert err.column == "normal_force" and "10x" in err.message and "--allow-implausible" in err.message
    ds = read_rig_csv(tmp_path / "run.csv", allow_implausible=True)
    assert ds.attrs["allow_implausible"] == "yes" and "allowed (--allow-implausible): normal_force" in \
        ds.attrs["quality_report"]


def test_spread_median_matches_the_full_median():
    """The load median over MEDIAN_SAMPLES spread samples: within the spread's sampling error of the exact
    one (a uniform +-1 N noise on 5 N: the median's standard error is 1/(2 f(m) sqrt(n)) = 1/sqrt(n) N)."""
    from fivid.io.plausibility import MEDIAN_SAMPLES, plausibility_findings

    rng = np.random.default_rng(3)
    n = 40 * MEDIAN_SAMPLES
    fn = 6.5 + rng.uniform(-1, 1, n)  # 30 % above a nominal 5 N: the mismatch warning names the median
    ft = 0.3 * fn
    findings = plausibility_findings({"normal_load": 5.0}, {"normal_force": fn, "friction_force": ft})
    message = next(f.message for f in findings if f.subject == "normal_force")
    measured = float(message.split("measured normal load ")[1].split(" N")[0])
    assert abs(measured - np.median(fn)) < 5 / np.sqrt(MEDIAN_SAMPLES) + 5e-4  # 5 sigma + the 4-digit print


def test_time_in_ms_labelled_s_against_the_stated_rate(tmp_path):
    rows = [with_field(r, 0, f"{1e3 * i / 51200:.9f}") for i, r in enumerate(rig_rows(100))]
    err = _reject(tmp_path, rows=rows, extra_meta=["# sample_rate: 51.2 kHz"])
    assert err.key == "sample_rate" and "ratio is 0.001" in err.message


def test_report_survives_netcdf(tmp_path):
    from fivid.io import read_run, write_run

    ds = read_rig_csv(write_rig(tmp_path / "run.csv"))
    back = read_run(write_run(ds, tmp_path / "run.nc"))
    assert back.attrs["quality_report"] == ds.attrs["quality_report"]
    assert N_META_LINES and np.isfinite(back["normal_force"].values).all()
