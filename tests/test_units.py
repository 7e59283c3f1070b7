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
