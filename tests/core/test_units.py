import math

import numpy as np
import pytest

from fivid.errors import UnitError
from fivid.units import conversion, convert, is_compatible, parse_quantity

# A parsed quantity is the number times a factor pint builds from exact decimal definitions
# (1 in = 0.0254 m, 1 g_n = 9.80665 m s-2, SI prefixes): one multiplication, and the factor itself
# may be 1 ulp off, so at most 2 roundings of 2**-53 each: rel 2 * 2**-52 (measured: 0 ulp today).
RTOL = 2 * 2.0**-52


@pytest.mark.parametrize(
    "text, to, expected",
    [
        ("10 mm/s", "m s-1", 0.01),
        ("5 N", "N", 5.0),
        ("0.8 um", "m", 0.8e-6),
        ("0.8 µm", "m", 0.8e-6),
        ("0.8 μm", "m", 0.8e-6),
        ("1.5 kN", "N", 1500.0),
        ("51.2 kHz", "Hz", 51200.0),
        ("2 ms", "s", 0.002),
        ("210 GPa", "Pa", 210e9),
        ("7850 kg/m^3", "kg m-3", 7850.0),
        ("1 g", "m s-2", 9.80665),
        ("3 g", "m s-2", 3 * 9.80665),
        ("1 in", "m", 0.0254),
    ],
)
def test_parse_quantity_to_si(text, to, expected):
    assert parse_quantity(text, to) == pytest.approx(expected, rel=RTOL)


def test_g_is_gram_unless_acceleration():
    assert parse_quantity("1 g", "kg") == pytest.approx(1e-3, rel=RTOL)


def test_udunits_exponents():
    assert conversion("m s-2", "m/s^2") == (1.0, 0.0)
    assert conversion("mm s-1", "m s-1")[0] == pytest.approx(1e-3, rel=RTOL)


def test_offset_units():
    scale, offset = conversion("degC", "K")
    assert scale == pytest.approx(1.0, rel=RTOL) and offset == pytest.approx(273.15, rel=RTOL)


def test_convert_array():
    x = np.array([0.0, 1.0, -2.0])
    np.testing.assert_allclose(convert(x, "g", "m s-2"), x * 9.80665, rtol=RTOL, atol=0)


@pytest.mark.parametrize(
    "text, to, fragment",
    [
        ("10 furlongz", "m", "cannot parse"),
        ("10 mm/s", "N", "not compatible"),
        ("10", "m s-1", "has no unit"),
        ("fast", "m s-1", "cannot read"),
    ],
)
def test_bad_quantities_name_the_value(text, to, fragment):
    with pytest.raises(UnitError, match=fragment) as info:
        parse_quantity(text, to)
    assert text.split()[0] in str(info.value) or text in str(info.value)


def test_bare_number_with_default_units():
    assert parse_quantity(10, "m s-1", default_units="mm/s") == pytest.approx(0.01, rel=RTOL)
    assert parse_quantity("0.3", "1") == 0.3
    assert not is_compatible("kg", "m")
    assert math.isclose(parse_quantity("1e-3 m", "mm"), 1.0, rel_tol=RTOL)


# ---- one home (issue 20 item 4): the rig readers' and the spectra's unit helpers are fivid.units' own ----

def test_rig_quantities_only_call_into_units():
    import fivid.io.rig_quantities as rq
    import fivid.units as u

    assert rq.sensitivity_factor is u.sensitivity_factor and rq.NUMBER is u.NUMBER


def test_unit_helpers_have_one_home():
    """No module but fivid/units.py defines a function named like one of fivid.units' public helpers (a copy of
    ``parse_quantity``, ``sensitivity_factor`` ... elsewhere fails here, wherever it is written)."""
    import ast
    from pathlib import Path

    import fivid.units as u

    helpers = {name for name in u.__all__ if callable(getattr(u, name))}
    assert {"parse_quantity", "sensitivity_factor", "convert"} <= helpers
    pkg = Path(u.__file__).parent
    copies = [f"{path.relative_to(pkg.parent)}:{node.lineno}: {node.name}"
              for path in sorted(pkg.rglob("*.py")) if path.name != "units.py" or path.parent != pkg
              for node in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
              if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.name in helpers]
    assert not copies, "unit helpers defined outside fivid/units.py:\n" + "\n".join(copies)


@pytest.mark.parametrize("text, decimal, expected", [
    ("0,8 um", ",", 0.8e-6),
    ("0.8 um", ",", 0.8e-6),      # a point is still read in a decimal-comma file
    ("1,5e3 mm/s", ",", 1.5),
    ("-2,5 N", ",", -2.5),
    (",5 s", ",", 0.5),
])
def test_decimal_comma(text, decimal, expected):
    assert parse_quantity(text, _si(text), decimal=decimal) == pytest.approx(expected, rel=RTOL)


def _si(text):
    return {"um": "m", "mm/s": "m s-1", "N": "N", "s": "s"}[text.split()[-1]]


def test_decimal_comma_is_refused_in_a_decimal_point_text():
    with pytest.raises(UnitError, match="comma"):
        parse_quantity("0,8 um", "m")  # "0" then unit ",8 um": refused (pint alone gave 0 x 8 um = 0)
    with pytest.raises(UnitError, match="decimal mark"):
        parse_quantity("0.8 um", "m", decimal=";")


def test_metadata_value_reads_decimal_commas_through_units():
    from fivid.io.rig_quantities import metadata_value

    assert metadata_value("roughness_ra", "0,4 µm", decimal=",") == pytest.approx(4e-7, rel=RTOL)
    # a bare number with the profile's unit may use either mark (file names such as 'B7_v2,5_...')
    assert metadata_value("sliding_velocity", "2,5", default_units="mm/s") == pytest.approx(2.5e-3, rel=RTOL)
    assert metadata_value("sliding_velocity", "2.5", default_units="mm/s", decimal=",") == pytest.approx(2.5e-3,
                                                                                                       rel=RTOL)
    with pytest.raises(UnitError):
        metadata_value("roughness_ra", "0,4 µm")  # with a unit, the file's decimal point rules


@pytest.mark.parametrize("signal, psd, csd_with_n, frf_per_n", [
    ("m s-2", "m2 s-4 Hz-1", "m s-2 N Hz-1", "m s-2 N-1"),
    ("1", "Hz-1", "N Hz-1", "N-1"),
    ("m/s", "(m/s)2 Hz-1", "(m/s) N Hz-1", "(m/s) N-1"),  # not a product of powers: bracketed, not guessed
])
def test_spectral_unit_strings_parse_back_to_the_right_dimension(signal, psd, csd_with_n, frf_per_n):
    from fivid.units import power_units, product_units, ratio_units

    assert power_units(signal) == psd and product_units(signal, "N") == csd_with_n
    assert ratio_units(signal, "N") == frf_per_n
    if signal != "m/s":  # the registry's style reads back through pint with the dimension of the product
        assert is_compatible(psd, "m2 s-4 Hz-1" if signal == "m s-2" else "s")
        assert is_compatible(frf_per_n, "m s-2 N-1" if signal == "m s-2" else "N-1")


@pytest.mark.parametrize("text, to", [("1,5 mm", "m"), ("2,5 mm/s", "m s-1"), ("0,8 um", "m")])
def test_a_decimal_comma_where_none_is_declared_is_an_error_not_a_product(text, to):
    # pint reads "1,5 mm" as 1 x (5 mm): 5 mm, silently wrong; fivid.units refuses it and says why
    with pytest.raises(UnitError, match="comma"):
        parse_quantity(text, to)
    assert parse_quantity(text, to, decimal=",") == pytest.approx(float(text.split()[0].replace(",", ".")) *
                                                                  {"mm": 1e-3, "mm/s": 1e-3, "um": 1e-6}[text.split()[1]],
                                                                  rel=RTOL)
