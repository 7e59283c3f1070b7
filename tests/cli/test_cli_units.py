"""Quantities with units on the command line (issue 19): one argparse type for every physical option."""

import pickle
from pathlib import Path

import pytest

from fivid.cli import QuantityArgument, build_parser, main, quantity
from fivid.cli import _verbosity

ROOT = Path(__file__).resolve().parents[2]
MODEL = str(ROOT / "configs/models/triboair_coarse.yaml")

# (argv before the option, option, number of values, SI unit, the same value written with a unit)
PHYSICAL_OPTIONS = [
    (["score", "M.nc", "S.nc"], "--band", 2, "Hz", "5 kHz"),
    (["damper", "frf", "D.yaml"], "--normal-load", 1, "N", "500 mN"),
    (["modes", MODEL], "--load", 1, "N", "500 mN"),
    (["cea", MODEL, "--mu", "0", "1", "3"], "--load", 1, "N", "500 mN"),
    (["simulate", MODEL, "-o", "x.nc"], "--velocity", 1, "m s-1", "10 mm/s"),
    (["simulate", MODEL, "-o", "x.nc"], "--load", 1, "N", "500 mN"),
    (["simulate", MODEL, "-o", "x.nc"], "--roughness", 1, "m", "0.8 um"),
    (["simulate", MODEL, "-o", "x.nc"], "--duration", 1, "s", "20 ms"),
    (["simulate", MODEL, "-o", "x.nc"], "--sample-rate", 1, "Hz", "5 kHz"),
    (["simulate", MODEL, "-o", "x.nc"], "--time-step", 1, "s", "20 ms"),
    (["profile", "P.csv"], "--window", 2, "m", "0.8 um"),
    (["profile", "P.csv"], "--cutoff", 1, "m", "0.8 um"),
    (["profile", "P.csv"], "--short-cutoff", 1, "m", "0.8 um"),
]
_SI = {"Hz": 5000.0, "N": 0.5, "m s-1": 0.01, "m": 0.8e-6, "s": 0.02}
_WRONG = {"Hz": "3 kg", "N": "3 s", "m s-1": "3 N", "m": "3 Hz", "s": "3 m"}
_NAMES = {"Hz": "frequency", "N": "force", "m s-1": "velocity", "m": "length", "s": "time"}


def _dest(option):
    return option.lstrip("-").replace("-", "_")


@pytest.mark.parametrize("argv, option, n, units, text", PHYSICAL_OPTIONS)
def test_a_quantity_with_a_unit_is_parsed_into_si(argv, option, n, units, text):
    args = build_parser().parse_args(argv + [option] + [text] * n)
    value = getattr(args, _dest(option))
    values = value if isinstance(value, list) else [value]
    assert [float(v) for v in values] == pytest.approx([_SI[units]] * n, rel=1e-12)
    assert all(v.text == text for v in values)  # the spelling is kept for the history line


@pytest.mark.parametrize("argv, option, n, units, text",
                         [o for o in PHYSICAL_OPTIONS if o[0][0] != "profile"])
def test_a_bare_number_is_in_the_si_unit_named_in_the_help(argv, option, n, units, text, capsys):
    args = build_parser().parse_args(argv + [option] + [repr(_SI[units])] * n)
    value = getattr(args, _dest(option))
    values = value if isinstance(value, list) else [value]
    assert [float(v) for v in values] == [_SI[units]] * n
    with pytest.raises(SystemExit):
        main(argv[:1] + (["frf"] if argv[0] == "damper" else []) + ["--help"])
    assert "bare number" in capsys.readouterr().out.replace("\n", " ").replace("  ", " ")


@pytest.mark.parametrize("argv, option, n, units, text", PHYSICAL_OPTIONS)
def test_a_wrong_dimension_is_exit_2_naming_option_value_and_dimension(argv, option, n, units, text, capsys):
    wrong = _WRONG[units]
    assert main(argv + [option] + [wrong] * n) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1, err
    assert f"argument {option}: '{wrong}' is not a {_NAMES[units]}" in err and "Traceback" not in err


def test_profile_lengths_refuse_bare_numbers(capsys):
    """A profilometer shows um: '468' meaning 468 m is a slip, so profile lengths need their unit."""
    assert main(["profile", "P.csv", "--cutoff", "80"]) == 2
    assert "'80' has no unit" in capsys.readouterr().err


@pytest.mark.parametrize("text, words", [("nan", "not a number with a unit"), ("1e999 N", "not finite"),
                                         ("0 N", "must be a positive force"), ("5 parsec", "is not a force")])
def test_out_of_range_values(text, words):
    import argparse

    with pytest.raises(argparse.ArgumentTypeError, match=words):
        quantity("N", positive=True)(text)


def test_a_parsed_quantity_is_a_float_that_pickles():
    q = quantity("m s-1")("10 mm/s")
    assert isinstance(q, float) and q == pytest.approx(0.01)
    back = pickle.loads(pickle.dumps(q))
    assert isinstance(back, QuantityArgument) and back == q and back.text == "10 mm/s"


@pytest.mark.parametrize("argv, level", [
    (["psd", "R.nc", "-o", "P.nc"], 0),
    (["-v", "psd", "R.nc", "-o", "P.nc"], 1),
    (["psd", "R.nc", "-o", "P.nc", "-v"], 1),
    (["-v", "psd", "R.nc", "-v", "-o", "P.nc"], 2),
    (["psd", "R.nc", "-o", "P.nc", "-q"], -1),
    (["damper", "fit", "L.json", "-vv"], 2),
])
def test_verbosity_before_or_after_the_command(argv, level):
    assert _verbosity(build_parser().parse_args(argv)) == level


def test_no_command_parses_quantities_itself():
    """One helper (fivid.cli.quantity) for every option: no command module calls parse_quantity."""
    commands = ROOT / "fivid" / "cli" / "commands"
    offenders = [p.name for p in commands.glob("*.py") if "parse_quantity" in p.read_text(encoding="utf-8")]
    assert not offenders
