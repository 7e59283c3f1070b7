"""Property tests: reported line numbers are the file's own whatever the layout (blank lines, CRLF,
BOM, metadata count); decimal-comma DAQ exports round-trip bit for bit through a rig profile."""

import tempfile
from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from tests.helpers.ingest import GOOD_META, HEADER, rig_rows, with_field

from fivid.errors import FividError
from fivid.io import read_rig_csv
from fivid.io.rig_profile import rig_profile_from_mapping

MARK = "1.5@bad"


@settings(max_examples=30, deadline=None)
@given(
    n=st.integers(min_value=3, max_value=60),
    data=st.data(),
    crlf=st.booleans(),
    bom=st.booleans(),
    comments=st.integers(min_value=0, max_value=3),
)
def test_error_line_is_the_line_of_the_bad_value(n, data, crlf, bom, comments):
    """The oracle is the text itself: the 1-based index of the line that holds the bad value."""
    bad_row = data.draw(st.integers(min_value=0, max_value=n - 1))
    blanks = data.draw(st.lists(st.integers(min_value=0, max_value=n), max_size=4))
    rows = rig_rows(n)
    rows[bad_row] = with_field(rows[bad_row], 2, MARK)
    body = []
    for i, row in enumerate(rows):
        body += [""] * blanks.count(i)
        body.append(row)
    lines = ["# fivid-rig-csv: 1"] + ["# a comment"] * comments + [f"# {k}: {v}" for k, v in GOOD_META.items()]
    lines += [HEADER] + body
    expected = next(i for i, line in enumerate(lines) if MARK in line) + 1
    newline = "\r\n" if crlf else "\n"
    text = ("\ufeff" if bom else "") + newline.join(lines) + newline
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "p.csv"
        path.write_bytes(text.encode("utf-8"))
        try:
            read_rig_csv(path)
        except FividError as err:
            assert err.line == expected, str(err)
            assert err.column == "friction_force"
        else:
            raise AssertionError("the bad value was accepted")


DAQ = {
    "fivid-rig-profile": 1,
    "format": "table",
    "csv": {"delimiter": ";", "decimal": ","},
    "metadata": {"values": {"run_id": "P1", "rig": "r", "sliding_velocity": "1 mm/s", "normal_load": "1 N",
                            "roughness_ra": "1 um"}},
    "columns": {"time": {"name": "t", "units": "s"}, "acceleration": {"name": "a", "units": "m s-2"},
                "friction_force": {"name": "ft", "units": "N"}, "normal_force": {"name": "fn", "units": "N"}},
}


def values(lo, hi):
    return st.floats(min_value=lo, max_value=hi, allow_nan=False, allow_infinity=False, allow_subnormal=False)


# the plausible range (fivid.io.plausibility rejects what no rig produces): |a| <= 1e6 m s-2, |F| <= 1e5 N,
# and a normal force that is not reversed and within 10x of the profile's normal_load (1 N)
@settings(max_examples=25, deadline=None)
@given(columns=st.lists(st.tuples(values(-1e6, 1e6), values(-1e5, 1e5), values(0.2, 9.9)), min_size=2, max_size=30),
       preamble=st.lists(st.sampled_from(["Export;v1", "Operator;X", "", "Note: a;b"]), max_size=4))
def test_decimal_comma_export_round_trips_exactly(columns, preamble):
    profile = rig_profile_from_mapping(DAQ)
    time = np.arange(len(columns)) / 1000.0
    rows = [";".join(repr(float(v)).replace(".", ",") for v in (t, *c)) for t, c in zip(time, columns)]
    text = "\n".join(preamble + ["t;a;ft;fn"] + rows) + "\n"
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "x.csv"
        path.write_text(text, encoding="utf-8")
        ds = read_rig_csv(path, profile)
    np.testing.assert_array_equal(ds["time"].values, time)
    for k, name in enumerate(["acceleration", "friction_force", "normal_force"]):
        np.testing.assert_array_equal(ds[name].values, [c[k] for c in columns])


@settings(max_examples=200, deadline=None)
@given(n=st.integers(2, 60), seed=st.integers(0, 2**32 - 1),
       kind=st.sampled_from(["clean", "jitter", "gap", "repeat", "backwards", "coarse"]))
def test_one_pass_time_checks_agree_with_the_individual_ones(n, seed, kind):
    """time_finding (one diff, min/max, a spread median) gives exactly the finding of the three checks run
    in order (the reference: each on the whole column)."""
    from fivid.io.data_checks import sampling_deviation, time_finding, time_not_increasing, time_without_resolution

    rng = np.random.default_rng(seed)
    time = np.arange(n) / 51200.0
    if kind == "jitter":
        time = time + rng.uniform(-1, 1, n) * 2e-7
    elif kind == "gap" and n > 3:
        time[rng.integers(1, n):] += 1 / 51200.0
    elif kind == "repeat":
        time[rng.integers(1, n)] = time[rng.integers(0, n - 1)]
    elif kind == "backwards":
        time = time[rng.permutation(n)]
    elif kind == "coarse":
        time = np.round(time, 4)
    tolerance = 0.01
    reference = time_without_resolution(time, tolerance) or time_not_increasing(time) or (
        sampling_deviation(time, tolerance) if time.size >= 3 else None)
    assert time_finding(time, tolerance) == reference
