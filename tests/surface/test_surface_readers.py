"""Profile readers: units to metres, and every bad input a clean fivid error naming file, line, column, value."""

import sys

import numpy as np
import pytest

from fivid.cli import main
from fivid.errors import DataQualityError, FividError, SchemaError, UnitError
from fivid.surface import read_profile, read_x3p


def _write(tmp_path, text, name="p.csv", encoding="utf-8"):
    path = tmp_path / name
    path.write_bytes(text.encode(encoding))
    return path


def _rows(n=10, fmt="{x},{z}"):
    return "".join(fmt.format(x=i * 0.5, z=(-1) ** i * 0.25) + "\n" for i in range(n))


def test_generic_csv_mm_and_um_to_metres(tmp_path):
    p = read_profile(_write(tmp_path, "# trace 7, stylus 2 um\nx [mm],z [um]\n" + _rows()))
    assert p["x"].values == pytest.approx(np.arange(10) * 0.5e-3)
    assert p.values == pytest.approx((-1) ** np.arange(10) * 0.25e-6)
    assert p.attrs["units"] == "m" and p["x"].attrs["units"] == "m"
    assert p.attrs["comments"] == "trace 7, stylus 2 um" and p.attrs["source"].startswith("p.csv sha256:")


@pytest.mark.parametrize("header, sep", [("x [nm]\tz [Å]", "\t"), ("x [µm]; z [nm]", ";"), ("x [um]  z [nm]", " ")])
def test_generic_text_separators_and_units(tmp_path, header, sep):
    p = read_profile(_write(tmp_path, header + "\n" + _rows(fmt="{x}" + sep + "{z}"), name="p.txt"))
    scale = {"nm": 1e-9, "µm": 1e-6, "um": 1e-6}[header.split("[")[1].split("]")[0]]
    assert p["x"].values[1] == pytest.approx(0.5 * scale)


@pytest.mark.parametrize("text, error, where, words", [
    ("x [um],z [um]\n0,1\n0.5,abc\n" + _rows(8), DataQualityError, ":3: column 'z [um]'", "'abc' is not a number"),
    ("x [um],z [um]\n0,1\n0.5\n" + _rows(8), SchemaError, ":3", "1 field(s)"),
    ("x [um],z [um]\n" + _rows(5) + "1.0,3\n" + _rows(5), DataQualityError, ":7: column 'x [um]'",
     "not strictly increasing: 1.0 after 2.0"),
    ("x [um],z [um]\n0,1\n1,2\n", DataQualityError, ":1", "2 data row(s)"),
    ("x [furlongs_per_um],z [um]\n" + _rows(), UnitError, ":1: column 'x [furlongs_per_um]'", "furlongs"),
    ("x [s],z [um]\n" + _rows(), UnitError, ":1: column 'x [s]'", "length unit"),
    ("x,z [um]\n" + _rows(), UnitError, ":1: column 'x'", "no unit"),
    ("x [um] | z [um]\n" + _rows(), SchemaError, ":2", "1 field(s)"),  # white-space separated: 1 field
    ("x [um],z [um]\n0,1\n0.5,nan\n" + _rows(8), DataQualityError, ":3: column 'z [um]'", "not a finite number"),
    ("# only a comment\n", SchemaError, ": ", "no header"),
])
def test_generic_bad_inputs(tmp_path, text, error, where, words):
    path = _write(tmp_path, text)
    with pytest.raises(error) as info:
        read_profile(path)
    msg = str(info.value)
    assert str(path) + where in msg and words in msg, msg


def _dektak_text(real_data):
    return (real_data / "profiles" / "dektak-1.csv").read_bytes().decode("latin-1")


def test_dektak_bad_value_names_line_and_column(real_data, tmp_path):
    lines = _dektak_text(real_data).split("\n")
    k = next(i for i, line in enumerate(lines) if line.startswith("Lateral")) + 101
    lines[k] = lines[k].replace(",", ",x", 1)
    path = _write(tmp_path, "\n".join(lines), name="dk.csv", encoding="latin-1")
    with pytest.raises(DataQualityError, match=rf"dk\.csv:{k + 1}: column 'Raw Micrometer': value 'x"):
        read_profile(path)
    assert main(["profile", str(path)]) == 2


def test_dektak_bad_unit_and_missing_block(real_data, tmp_path):
    text = _dektak_text(real_data)
    path = _write(tmp_path, text.replace("Raw Micrometer", "Raw Parsec per second"), "dk.csv", "latin-1")
    with pytest.raises(UnitError, match=r"dk\.csv:\d+: column 'Raw Parsec per second'"):
        read_profile(path)
    # without the Scan Data block the file is not recognised as a Dektak export: the generic reader says why
    path = _write(tmp_path, text.replace("Scan Data", "Scan Dota"), "dk2.csv", "latin-1")
    with pytest.raises(FividError, match=r"dk2\.csv:1"):
        read_profile(path)


def test_dektak_printed_x_is_used_when_it_is_not_the_regular_grid(real_data, tmp_path):
    lines = _dektak_text(real_data).split("\n")
    k = next(i for i, line in enumerate(lines) if line.startswith("Lateral")) + 51
    x, rest = lines[k].split(",", 1)
    lines[k] = f"{float(x) + 0.07:.1f},{rest}"
    p = read_profile(_write(tmp_path, "\n".join(lines), "dk.csv", "latin-1"))
    assert p.attrs["x_coordinate"] == "as printed"


def test_missing_file_is_a_clean_error(tmp_path, capsys):
    assert main(["profile", str(tmp_path / "nope.csv")]) == 2
    assert "not found" in capsys.readouterr().err


def test_x3p_without_x3pio_says_how_to_install(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "x3pio", None)  # import x3pio raises ImportError
    path = tmp_path / "a.x3p"
    path.write_bytes(b"PK")
    with pytest.raises(FividError, match="pip install x3pio"):
        read_profile(path)


def test_x3p_profile_round_trip(tmp_path):
    x3pio = pytest.importorskip("x3pio")
    z = 1e-6 * np.sin(np.arange(500) / 7.0)
    path = tmp_path / "p.x3p"
    x3pio.write(str(path), z, x_scale=0.5e-6)
    p = read_x3p(path)
    assert p.values == pytest.approx(z, rel=1e-12, abs=1e-18)
    assert p["x"].values[1] == pytest.approx(0.5e-6) and p.attrs["x3p_feature"] == "Profile"
    surface = tmp_path / "s.x3p"
    x3pio.write(str(surface), np.vstack([z, 2 * z]), x_scale=0.5e-6, y_scale=1e-6)
    with pytest.raises(SchemaError, match="row="):
        read_x3p(surface)
    assert read_x3p(surface, row=1).values == pytest.approx(2 * z)
