"""Law objects: Coulomb, perturbed Coulomb (PSD integral, sampling, convection), amplitude forms, law file."""

import numpy as np
import pytest

from fivid.errors import FividError, SchemaError
from fivid.friction import (
    AmplitudeModel,
    CoulombLaw,
    PerturbedCoulombLaw,
    law_dataset,
    load_law,
    write_law,
)

RA = 0.8e-6  # [m]
F = np.linspace(100.0, 8000.0, 400)
SHAPE = 1.0 / (1.0 + (F / 1500.0) ** 4)


def linear_model():
    return AmplitudeModel(
        "linear_velocity",
        np.array([0.002, 0.4, 0.001, 0.9]),
        ("intercept[0]", "velocity_slope[0]", "intercept[1]", "velocity_slope[1]"),
        np.full(4, 1e-4),
        np.eye(4) * 1e-8,
        terms=("sliding_velocity", "roughness_ra"),
        roughness_levels=(0.4e-6, 0.8e-6),
    )


def power_model():
    return AmplitudeModel(
        "power_law_load",
        np.array([np.log(0.003), 0.5, 0.8, -0.2]),
        ("log_prefactor", "roughness_exponent", "velocity_exponent", "load_exponent"),
        np.full(4, 0.01),
        np.eye(4) * 1e-4,
        terms=("roughness_ra", "sliding_velocity", "normal_load"),
    )


def test_amplitude_forms_match_closed_forms():
    lin = linear_model()
    assert lin(0.01, 0.8e-6)[0] == pytest.approx(0.001 + 0.9 * 0.01, rel=1e-14)
    assert lin(0.01, 0.4e-6 * 1.005)[0] == pytest.approx(0.002 + 0.4 * 0.01, rel=1e-14)
    pw = power_model()
    expected = 0.003 * (RA / 1e-6) ** 0.5 * (0.01 / 1e-3) ** 0.8 * (5.0 / 1.0) ** -0.2
    assert pw(0.01, RA, 5.0)[0] == pytest.approx(expected, rel=1e-13)


def test_linear_form_refuses_unknown_roughness():
    with pytest.raises(FividError, match=r"Ra = 3\.2 um .* \(0\.4 um, 0\.8 um\)"):
        linear_model()(0.01, 3.2e-6)


def test_missing_factors_are_named():
    with pytest.raises(FividError, match="normal_load"):
        power_model()(0.01, RA)
    with pytest.raises(FividError, match=r"depends on roughness_ra: pass roughness_ra > 0 \(got none\)"):
        power_model()(0.01, None, 5.0)
    with pytest.raises(FividError, match="depends on the roughness"):
        linear_model()(0.01, None)


def test_psd_integrates_to_amplitude_squared():
    law = PerturbedCoulombLaw(0.3, F, SHAPE, linear_model(), (100.0, 8000.0))
    fine = np.linspace(0.0, 10000.0, 200001)
    a = law.amplitude(0.01, RA)
    # trapezoid on 0.05 Hz steps of a piecewise-linear function: exact up to the two band-edge cells
    assert np.trapezoid(law.psd(fine, 0.01, RA), fine) == pytest.approx(a**2, rel=1e-4)
    assert law.psd(np.array([50.0, 9000.0]), 0.01, RA).tolist() == [0.0, 0.0]


def test_convected_psd_scales_with_velocity_and_keeps_its_integral():
    law = PerturbedCoulombLaw(0.3, F, SHAPE, linear_model(), (100.0, 8000.0), injection="convected",
                              reference_velocity=0.01)
    fine = np.linspace(0.0, 40000.0, 400001)
    for v in (0.005, 0.01, 0.02):
        p = law.psd(fine, v, RA)
        assert np.trapezoid(p, fine) == pytest.approx(law.amplitude(v, RA) ** 2, rel=1e-3)
    # a frozen field at twice the speed: the same shape stretched by 2 in frequency
    p1 = law.psd(np.array([1000.0]), 0.01, RA) / law.amplitude(0.01, RA) ** 2
    p2 = law.psd(np.array([2000.0]), 0.02, RA) / law.amplitude(0.02, RA) ** 2
    assert p2[0] == pytest.approx(p1[0] / 2, rel=1e-12)


def test_sample_has_the_law_rms():
    law = PerturbedCoulombLaw(0.3, F, SHAPE, power_model(), (100.0, 8000.0))
    x = law.sample(1.0, 20480.0, 0.01, RA, seed=2, n_signals=8, normal_load=5.0)
    assert x.shape == (8, 20480)
    a = law.amplitude(0.01, RA, 5.0)
    # the discrete shape is renormalised on the synthesis grid: E[mean square] = A^2 exactly; each
    # record's mean square has relative sd sqrt(Σ s_k^2)/Σ s_k ≈ 1/sqrt(B T) with B the equivalent
    # bandwidth of the shape (≈ 1.6 kHz) and T = 1 s: ≈ 0.025; the mean of 8 is within 4 sd / sqrt(8)
    ms = np.mean(x**2, axis=1)
    f = np.arange(10241) * 20480.0 / 20480
    s = law.normalised_shape(f)
    rel_sd = np.sqrt(np.sum(s**2)) / np.sum(s)
    assert abs(ms.mean() / a**2 - 1) < 4 * rel_sd / np.sqrt(8)
    np.testing.assert_array_equal(x, law.sample(1.0, 20480.0, 0.01, RA, seed=2, n_signals=8, normal_load=5.0))


def test_sample_refuses_a_record_without_bins_in_band():
    law = PerturbedCoulombLaw(0.3, F, SHAPE, linear_model(), (100.0, 8000.0))
    with pytest.raises(FividError, match="no frequency bin inside"):
        law.sample(1.0, 100.0, 0.01, RA, seed=0)  # Nyquist 50 Hz, band from 100 Hz
    with pytest.raises(FividError, match="at least 4"):
        law.sample(0.001, 100.0, 0.01, RA, seed=0)


def test_coulomb_law():
    law = CoulombLaw(0.25)
    assert law.amplitude(0.01, RA) == 0
    assert np.all(law.sample(0.1, 1000.0, 0.01, RA, seed=0, n_signals=3) == 0)
    assert law.sample(0.1, 1000.0, 0.01, RA, seed=0, n_signals=3).shape == (3, 100)
    assert "0.25" in law.describe()
    with pytest.raises(FividError, match="mu0"):
        CoulombLaw(-0.1)


def test_law_file_round_trip(tmp_path):
    law = PerturbedCoulombLaw(0.31, F, SHAPE, linear_model(), (100.0, 8000.0), injection="per_node")
    path = write_law(law, tmp_path / "law.nc")
    back = load_law(path)
    assert back.sha256 == law.sha256
    assert back.injection == "per_node"
    assert back.amplitude(0.02, RA) == law.amplitude(0.02, RA)
    assert "sha256:" in back.source
    with pytest.raises(FividError, match="exists"):
        write_law(law, path)
    c = load_law(write_law(CoulombLaw(0.2), tmp_path / "c.nc"))
    assert isinstance(c, CoulombLaw) and c.mu0 == 0.2


def test_bad_law_files(tmp_path):
    with pytest.raises(FividError, match="no such file"):
        load_law(tmp_path / "missing.nc")
    (tmp_path / "junk.nc").write_text("not netcdf")
    with pytest.raises(SchemaError, match="cannot read"):
        load_law(tmp_path / "junk.nc")
    ds = law_dataset(PerturbedCoulombLaw(0.3, F, SHAPE, linear_model(), (100.0, 8000.0))).drop_vars("shape")
    ds.to_netcdf(tmp_path / "noshape.nc")
    with pytest.raises(SchemaError, match="missing shape"):
        load_law(tmp_path / "noshape.nc")


def test_law_file_round_trip_property(tmp_path_factory):
    """Any law (form, coefficients, band, injection) survives write/load with the same sha256 and values."""
    from hypothesis import given, settings
    from hypothesis import strategies as st

    @settings(max_examples=25, deadline=None)
    @given(
        form=st.sampled_from(["linear", "power"]),
        scale=st.floats(0.1, 10.0),
        mu0=st.floats(0.0, 1.0),
        lo=st.floats(0.0, 500.0),
        width=st.floats(100.0, 10000.0),
        injection=st.sampled_from(["uniform", "per_node", "convected"]),
    )
    def check(form, scale, mu0, lo, width, injection):
        model = linear_model() if form == "linear" else power_model()
        f = np.linspace(lo, lo + width, 50)
        law = PerturbedCoulombLaw(mu0, f, 1.0 + np.cos(f / width), model, (lo, lo + width), injection=injection,
                                  reference_velocity=0.01 if injection == "convected" else None).scaled(scale)
        path = tmp_path_factory.mktemp("law") / "law.nc"
        back = load_law(write_law(law, path))
        assert back.sha256 == law.sha256
        kw = dict(normal_load=5.0) if form == "power" else {}
        assert back.amplitude(0.01, 0.8e-6, **kw) == law.amplitude(0.01, 0.8e-6, **kw)
        np.testing.assert_array_equal(back.psd(f, 0.01, 0.8e-6, **kw), law.psd(f, 0.01, 0.8e-6, **kw))

    check()
