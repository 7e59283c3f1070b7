"""The reduced path's in-band error estimate (fivid/solver/reduced_error.py, issue 30 item 2): its pieces against
closed forms and the full model, and an undamped model's estimate."""

import math

import numpy as np
import pytest
import scipy.linalg

from fivid.fe.damping import modal_root
from fivid.fe.modal import constrained_matrices
from fivid.solver.driver import prepare_run
from fivid.solver.reduced_error import (
    HANN_HALF_WIDTH,
    band_error_estimate,
    contact_states,
    discrete_root,
    lorentzian_lsd_integral,
)
from tests.helpers.reduced_setup import coarse, run_inputs  # noqa: F401  (coarse is a fixture)

DB = 10.0 / math.log(10.0)


@pytest.mark.parametrize("dt", [1e-7, 5e-7])
def test_discrete_root_against_the_central_difference_closed_forms(dt):
    """Undamped: central differences give ``omega_num = (2 / dt) asin(omega dt / 2)`` exactly. Classic Rayleigh:
    the relative frequency error is ``(omega dt)^2 / 24 + zeta omega dt / 2`` (dispersion plus the damping force's
    half-step-old velocity) to first order; the next terms are ``(omega dt)^2`` and ``zeta`` times smaller (here
    <= 1e-3 and 1e-2 of it), so 2 %."""
    for f in (1e3, 1e4):
        w = 2.0 * math.pi * f
        s = discrete_root(f, 0.0, 0.0, None, dt)
        assert s.real == pytest.approx(0.0, abs=1e-9 * w)
        assert s.imag == pytest.approx(2.0 / dt * math.asin(w * dt / 2.0), rel=1e-12)
        alpha, beta = 50.4, 3.1e-7
        exact = complex(modal_root(f, alpha, beta))
        zeta = -exact.real / abs(exact)
        shift = discrete_root(f, alpha, beta, None, dt).imag / exact.imag - 1.0
        assert shift == pytest.approx((w * dt) ** 2 / 24.0 + zeta * w * dt / 2.0, rel=0.02)
        # a velocity filter far above the mode: the band-limited scheme tends to the classic one's root
        far = discrete_root(f, alpha, beta, 1e13, dt)
        assert far.imag == pytest.approx(discrete_root(f, alpha, beta, None, dt).imag, rel=1e-9)


def test_lorentzian_integral_on_a_part_of_the_line_against_its_small_shift_closed_form():
    """For ``d << 1`` the log ratio is ``-2 u d / (1 + u^2)`` (x 10/ln 10), whose square integrates to
    ``(20 d / ln 10)^2 [(atan u - u / (1 + u^2)) / 2]`` between the bounds (relative error O(d)); the parts of a
    split line add up to the whole."""
    d = 1e-3

    def closed(a, b):
        prim = lambda u: 0.5 * (math.atan(u) - u / (1.0 + u * u)) if math.isfinite(u) else math.copysign(math.pi / 4, u)
        return (2.0 * DB * d) ** 2 * (prim(b) - prim(a))

    for a, b in ((-3.0, 2.0), (4.0, 80.0), (-math.inf, -7.0), (-math.inf, math.inf)):
        assert lorentzian_lsd_integral(d, 1.0, a, b) == pytest.approx(closed(a, b), rel=5 * d)
    parts = sum(lorentzian_lsd_integral(0.3, 1.1, a, b) for a, b in ((-math.inf, -60.0), (-60.0, 1.0), (1.0, math.inf)))
    assert parts == pytest.approx(lorentzian_lsd_integral(0.3, 1.1), rel=1e-6)


def _full_rows(model, rs, rows):
    """``rows`` on the reduced system's free coordinates (boundary part only) as rows on the full model's free dofs."""
    nb = int(rs.kernel["nb"])
    index = {int(d): i for i, d in enumerate(model.free_dofs)}
    out = np.zeros((rows.shape[0], len(index)))
    for k in range(2 * nb):
        col = rows[:, k]
        if np.any(col):
            out[:, index[2 * int(rs.nodes[k % nb]) + k // nb]] = col
    assert not np.any(rows[:, 2 * nb:])  # ties act on the physical boundary coordinates only
    return out


def _tied_frequencies(K, M, rows, n):
    z = scipy.linalg.null_space(rows)
    lam = scipy.linalg.eigh(z.T @ K @ z, z.T @ M @ z, eigvals_only=True, subset_by_index=[0, n - 1])
    return np.sqrt(lam) / (2.0 * math.pi)


def test_contact_states_of_the_preload_are_the_full_models_tied_modes(coarse):
    """The estimate's linear contact states tie the slaves closed after the preload (on the coarse rig one corner
    node of the upper beam's 6, the beam resting on its free end): the reduced system's tied frequencies equal the
    full lumped model's with the same ties to 1e-3 (the truncation at 3 x the band top leaves ~1e-4, the
    truncation test). Tying every slave instead describes another system, 30-50 % stiffer in its first modes."""
    prep = prepare_run(coarse, **run_inputs(1e-3, reduced=True))
    rs, active = prep.reduced, prep.preload.active
    assert 0 < active.sum() < active.size
    K, M = (a.toarray() for a in constrained_matrices(coarse, mass="lumped")[:2])
    nf = rs.n_free
    for name in ("sliding", "stuck"):
        rows = contact_states(rs, active)[name]
        reduced = _tied_frequencies(rs.K[:nf, :nf], rs.M[:nf, :nf], rows, 3)
        full = _tied_frequencies(K, M, _full_rows(coarse, rs, rows), 3)
        np.testing.assert_allclose(reduced, full, rtol=1e-3)
        every = _tied_frequencies(rs.K[:nf, :nf], rs.M[:nf, :nf], contact_states(rs)[name], 3)
        assert every[0] > 1.25 * full[0]


def test_an_undamped_model_gets_a_finite_estimate_from_the_psd_resolution(coarse):
    """Zero damping (alpha = beta = 0): each peak is as wide as the Hann window makes it, ``0.72 Delta f``, so the
    estimate is finite (it divided by the damping ratio before); with the step's error alone and every peak well
    inside the band it is the Lorentzian sum with that width, ``LSD^2 = (1/B) sum w g(delta f_r / w)``, delta the
    exact undamped central-difference shift."""
    rs = prepare_run(coarse, **run_inputs(1e-3, reduced="reduced")).reduced
    band, dt, bin_width = (200.0, 10e3), 4e-7, 200.0
    est = band_error_estimate(rs, band, alpha=0.0, beta=0.0, damping_cutoff=math.inf, time_step=dt,
                              bin_width=bin_width)
    assert math.isfinite(est["lsd_db"]) and est["lsd_db"] > 0.0
    assert est["states"]["open"]["time_step_db"] > 0.0
    wider = band_error_estimate(rs, band, alpha=0.0, beta=0.0, time_step=dt, bin_width=2 * bin_width)
    assert wider["lsd_db"] < est["lsd_db"]  # coarser bins: wider peaks, a shift shows less
    with pytest.raises(ValueError, match="bin_width"):
        band_error_estimate(rs, band, alpha=0.0, beta=0.0, bin_width=0.0)
    # the same sum by hand for the open state, on a band that holds every mode well inside it
    wide = (10.0, 60e3)
    est = band_error_estimate(rs, wide, alpha=0.0, beta=0.0, time_step=dt, bin_width=bin_width)
    nf = rs.n_free
    lam = scipy.linalg.eigh(rs.K[:nf, :nf], rs.unscaled_mass[:nf, :nf], eigvals_only=True)
    f = np.sqrt(lam[lam < (2 * math.pi * 1.5 * 60e3) ** 2]) / (2 * math.pi)  # OUTSIDE_REACH x the band top
    w = HANN_HALF_WIDTH * bin_width
    shift = 2.0 / (2 * math.pi * f * dt) * np.arcsin(2 * math.pi * f * dt / 2.0) - 1.0
    by_hand = math.sqrt(sum(w * lorentzian_lsd_integral(s * fr / w, 1.0, (wide[0] - fr) / w, (wide[1] - fr) / w)
                            for s, fr in zip(shift, f)) / (wide[1] - wide[0]))
    assert est["states"]["open"]["time_step_db"] == pytest.approx(by_hand, rel=1e-6)
