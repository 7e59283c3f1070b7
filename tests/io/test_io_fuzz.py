"""Fuzz the readers (issue 18): any bytes give a dataset or a clean fivid error, never another exception.

Inputs are valid files put through grammar-aware mutations (lines dropped, duplicated, swapped or replaced
by pieces of the grammar, characters replaced, the file cut short, encodings and line ends changed) plus raw
bytes. The oracle: ``read_rig_csv`` / ``read_rig_head`` / ``read_profile`` return, or raise a
:class:`~fivid.errors.FividError` (which the CLI prints as one line and exit 2). Anything else is a crash.
Bounded (200 examples each, no deadline) so it stays in the fast suite.
"""

import os
import tempfile
import zipfile
from pathlib import Path

from hypothesis import example, HealthCheck, given, settings
from hypothesis import strategies as st
from tests.helpers.ingest import GOOD_META, HEADER, rig_rows, rig_text

from fivid.errors import FividError

# derandomize: the same 200 examples every run, so CI is reproducible (a new crash must not appear at random on
# main); set HYPOTHESIS_RANDOM=1 to explore beyond them locally
FUZZ = settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow],
                derandomize=not os.environ.get("HYPOTHESIS_RANDOM"))

# pieces of the rig-CSV and profile grammars, and values known to trouble parsers
_TOKENS = ["# fivid-rig-csv: 1", "# fivid-rig-csv: 2", "# run_id: R001", "# sample_rate: 51.2 kHz",
           "# sample_rate: 0 Hz", "# normal_load: -5 N", "# sliding_velocity: 1e400 mm/s", "# roughness_ra: nan um",
           "# rig:", "#", ":", HEADER, "time [s]", "time [ms],acceleration [g]", "acceleration [furlong]",
           "x [um],z [um]", "Scan Data", "Lateral um,Raw Micrometer,", "Scan Parameters", "Length,1500.0 um",
           "Analytical Results", "Ra,1 um,0 um,2 um,0 um,0.005 um", "R. Cursor,Pos: um Width:",
           "0", "-0", "1e308", "1e-320", "nan", "inf", "-inf", "1,2", "1;2", "1\t2", ",,,,", "\"", "\"a,b\"",
           "0x10", "1_000", "١٢٣", "\u00b5m", "\ufeff", "\x00", " ", "[", "]", "[ ]", "1.5@bad", "9" * 400]


def _valid_rig() -> str:
    return rig_text(rig_rows(12))


def _mutate(text: str, data) -> str:
    lines = text.split("\n")
    for _ in range(data.draw(st.integers(1, 4), label="n_mutations")):
        op = data.draw(st.sampled_from(["drop", "dup", "swap", "token", "chars", "cut", "field"]), label="op")
        i = data.draw(st.integers(0, max(len(lines) - 1, 0)), label="line")
        if not lines:
            lines = [""]
        if op == "drop" and len(lines) > 1:
            del lines[i]
        elif op == "dup":
            lines.insert(i, lines[i])
        elif op == "swap":
            j = data.draw(st.integers(0, len(lines) - 1), label="other")
            lines[i], lines[j] = lines[j], lines[i]
        elif op == "token":
            lines[i] = data.draw(st.sampled_from(_TOKENS), label="token")
        elif op == "chars":
            line = lines[i]
            k = data.draw(st.integers(0, len(line)), label="at")
            lines[i] = line[:k] + data.draw(st.text(max_size=6), label="text") + line[k + 1:]
        elif op == "cut":
            lines = lines[: i + 1]
            lines[-1] = lines[-1][: data.draw(st.integers(0, len(lines[-1])), label="cut_at")]
        else:  # one field of a delimited line replaced by a token
            fields = lines[i].split(",")
            f = data.draw(st.integers(0, len(fields) - 1), label="field")
            fields[f] = data.draw(st.sampled_from(_TOKENS), label="value")
            lines[i] = ",".join(fields)
    newline = data.draw(st.sampled_from(["\n", "\r\n", "\r"]), label="newline")
    return newline.join(lines)


def _encode(text: str, data) -> bytes:
    encoding = data.draw(st.sampled_from(["utf-8", "utf-8-sig", "latin-1", "utf-16"]), label="encoding")
    return text.encode(encoding, errors="replace")


def _read_or_clean_error(read, name: str, payload: bytes):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / name
        path.write_bytes(payload)
        try:
            read(path)
        except FividError as exc:
            assert str(exc).strip(), "an empty error message"


def _read_rig(path):
    from fivid.io import read_rig_csv

    return read_rig_csv(path)


def _read_rig_head(path):
    from fivid.io import read_rig_head

    return read_rig_head(path)


@FUZZ
@given(data=st.data())
def test_rig_csv_mutations_give_a_dataset_or_a_fivid_error(data):
    payload = _encode(_mutate(_valid_rig(), data), data)
    _read_or_clean_error(_read_rig, "R001_v10_ra08.csv", payload)


@FUZZ
@given(meta=st.dictionaries(st.sampled_from(sorted(GOOD_META) + ["sample_rate", "rig", "x"]),
                            st.text(max_size=12), max_size=6),
       header=st.lists(st.sampled_from(HEADER.split(",") + ["time", "time []", "z [um]", "acceleration [g"]),
                       min_size=1, max_size=6))
def test_rig_header_grammar_gives_a_head_or_a_fivid_error(meta, header):
    text = rig_text(rig_rows(5), meta={**GOOD_META, **meta}, header=",".join(header))
    _read_or_clean_error(_read_rig_head, "p.csv", text.encode("utf-8"))
    _read_or_clean_error(_read_rig, "p.csv", text.encode("utf-8"))


@FUZZ
@given(payload=st.binary(max_size=400))
@example(payload=b"\r\x01")  # a lone carriage return in the header line: csv.Error before the fix
def test_rig_csv_raw_bytes_give_a_fivid_error(payload):
    _read_or_clean_error(_read_rig, "p.csv", b"# fivid-rig-csv: 1\n" + payload)


def _read_profile(path):
    from fivid.surface import read_profile

    return read_profile(path)


_COLUMNS = "x [um],z [um]\n" + "".join(f"{i * 0.5},{(-1) ** i * 0.25}\n" for i in range(12))
_DEKTAK = "\n".join(["Scan Parameters", "Scan Type,Standard Scan", "Length,6.0 um", "Resolution,0.5 um/sample",
                     "Analytical Results", "Function,R.Cur Pos,R.Cur Width,M.Cur Pos,M.Cur Width,Result",
                     "Ra,0.0 um,0.0 um,6.0 um,0.0 um,0.25 um", "Scan Data", "Lateral um,Raw Micrometer,"]
                    + [f"{i * 0.5},{(-1) ** i * 0.25},," for i in range(12)]) + "\n"


@FUZZ
@given(data=st.data(), base=st.sampled_from([_COLUMNS, _DEKTAK]), name=st.sampled_from(["p.csv", "p.txt", "p.dat"]))
def test_profile_mutations_give_a_profile_or_a_fivid_error(data, base, name):
    _read_or_clean_error(_read_profile, name, _encode(_mutate(base, data), data))


@FUZZ
@given(payload=st.binary(max_size=300), zipped=st.booleans(), member=st.sampled_from(["main.xml", "x", "bindata/d"]))
def test_x3p_bytes_give_a_fivid_error(payload, zipped, member):
    import io

    if zipped:  # an .x3p is a zip archive: fuzz the member too
        buf = io.BytesIO()
        with zipfile.ZipFile(buf, "w") as z:
            z.writestr(member, payload)
        payload = buf.getvalue()
    _read_or_clean_error(_read_profile, "p.x3p", payload)
