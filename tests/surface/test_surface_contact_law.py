"""GW parameters from profiles (fivid.surface.contact_law, issue 27 item 2), checked against summits identified
directly on SYNTHETIC isotropic Gaussian surfaces (fivid.surface.contact_law.gaussian_random_surface), against the
closed-form moments of a Gaussian autocorrelation, and through ``fivid profile --contact-law``."""

import json
import math

import numpy as np
import pytest
import yaml

from fivid.cli import main
from fivid.errors import ConfigError
from fivid.surface import gaussian_random_profile
from fivid.surface.contact_law import (gaussian_random_surface, gw_config, gw_from_moments, gw_parameters,
                                       spectral_moments, surface_summits)

STEP = 1e-6  # [m]
XI = 10e-6  # correlation length [m] of the Gaussian ACF exp(-(r/xi)^2): 10 samples
SHAPES = {
    # radial spectrum of a Gaussian ACF: narrow band, alpha = 3
    "gaussian_acf": lambda q: np.exp(-(np.pi * q * XI) ** 2),
    # a band-limited power law (self-affine between 100 um and 10 um wavelengths): broader band, alpha ~ 6
    "power_law": lambda q: np.where((q > 1e4) & (q < 1e5), 1.0, 0.0) * np.maximum(q, 1e4) ** -3.6,
}


def _profile_moments(z):
    """Spectral moments averaged over every row and column of a surface (profiles in two directions)."""
    rows = [spectral_moments(r, STEP) for r in z] + [spectral_moments(c, STEP) for c in z.T]
    return np.mean(rows, axis=0)


@pytest.mark.parametrize("shape", sorted(SHAPES))
def test_profile_estimator_recovers_the_summits_of_a_gaussian_surface(shape):
    """McCool's estimator from the rows' and columns' moments vs the summits of the same 2D surface found as
    8-neighbour maxima: density, radius (1 / mean curvature) and summit-height deviation within 10 % (the issue's
    tolerance). The discrete summit count converges to Nayak's continuous density as the grid resolves the
    shortest wavelength (here >= 10 samples per wavelength: a few per cent); 512 x 512 samples give ~700-1800
    summits, a sampling scatter of the mean curvature and height deviation of ~2 %."""
    z = gaussian_random_surface(512, STEP, SHAPES[shape], 0.5e-6, seed=7)
    est = gw_from_moments(*_profile_moments(z))
    ref = surface_summits(z, STEP)
    assert ref["heights"].size > 400
    for key, ref_key in (("asperity_density", "density"), ("asperity_radius", "radius"), ("sigma", "sigma")):
        assert est[key] == pytest.approx(ref[ref_key], rel=0.10), key
    assert est["mean_summit_height"] == pytest.approx(np.mean(ref["heights"]), rel=0.10)


def test_estimator_on_a_gaussian_acf_profile_matches_the_closed_form():
    """A 1D Gaussian-ACF profile (fivid.surface.gaussian_random_profile, SYNTHETIC) has m0 = sigma^2,
    m2 = 2 sigma^2/xi^2, m4 = 12 sigma^2/xi^4, so alpha = 3, eta = 1/(pi sqrt(3) xi^2),
    R = 0.375 xi^2 sqrt(pi/12)/sigma: recovered within the scatter of a 4 mm record (400 correlation lengths:
    m0 ~ 3 %, m4 ~ 5 %) plus the second difference's bias (k h)^2/12 ~ 1 % at 20 samples per xi."""
    sigma, xi, step = 0.5e-6, 10e-6, 0.5e-6
    p = gaussian_random_profile(sigma, xi, 4e-3, step, seed=3)
    gw = gw_parameters(p.values, step)
    assert gw["alpha"] == pytest.approx(3.0, rel=0.1)
    assert gw["asperity_density"] == pytest.approx(1.0 / (math.pi * math.sqrt(3.0) * xi**2), rel=0.1)
    assert gw["asperity_radius"] == pytest.approx(0.375 * xi**2 * math.sqrt(math.pi / 12.0) / sigma, rel=0.1)
    assert gw["sigma"] == pytest.approx(math.sqrt(1 - 0.8968 / 3.0) * sigma, rel=0.1)


def test_bad_profiles_are_refused():
    with pytest.raises(ConfigError, match="flat profile"):
        gw_from_moments(0.0, 1.0, 1.0)
    with pytest.raises(ConfigError, match="below 1.5"):
        gw_from_moments(1.0, 1.0, 1.0)  # alpha 1: no isotropic Gaussian surface
    with pytest.raises(ConfigError, match="at least 5"):
        spectral_moments([1.0, 2.0], 1e-6)


def test_gw_config_is_a_model_config_normal_block():
    """The block loads as a Greenwood-Williamson law with the same numbers (fivid.contact.config)."""
    from fivid.contact.config import NormalLawConfig, normal_law

    block = gw_config({"sigma": 4e-7, "asperity_radius": 4e-5, "asperity_density": 1.8e9})
    law = normal_law(NormalLawConfig.model_validate({**block, "e_star": "115 GPa"}))
    assert "sigma 4e-07 m" in law.source and "asperity radius 4e-05 m" in law.source and "density 1.8e+09" in law.source


def test_profile_cli_writes_the_contact_law(tmp_path, capsys):
    """``fivid profile FILE --contact-law OUT.yaml --json`` on a synthetic Gaussian-ACF profile: the YAML's
    ``normal:`` block carries the estimator's numbers."""
    p = gaussian_random_profile(0.5e-6, 10e-6, 2e-3, 0.5e-6, seed=5)
    csv = tmp_path / "p.csv"
    np.savetxt(csv, np.c_[p["x"].values * 1e6, p.values * 1e6], delimiter=",", header="x [um],z [um]", comments="")
    out = tmp_path / "gw.yaml"
    assert main(["profile", str(csv), "--contact-law", str(out), "--json"]) == 0
    s = json.loads(capsys.readouterr().out)["contact_law"]
    block = yaml.safe_load(out.read_text())["normal"]
    assert block["law"] == "greenwood-williamson"
    assert float(block["asperity_density"].split()[0]) == pytest.approx(s["asperity_density"], rel=1e-3)
    assert s["alpha"] == pytest.approx(3.0, rel=0.15)
