"""Seed 002's stick-slip by the paper's own marks (fivid.study.analysis.zone_stick_slip; Massi et al., p. 7, Fig. 8):
a stick zone that releases, and a response that is not harmonic.

All records here are SYNTHETIC, generated in this file with known class by construction: tones of known frequency
and power (the harmonic share in closed form: the dominant tone's comb over the total), and contact-state
histories (time x node) whose stick runs are laid out by hand -- a harmonic limit cycle's stick within each cycle
(shorter than a period by construction) against a stick zone of a few periods travelling along the contact.
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from fivid.study.analysis import HARMONIC_SHARE, harmonic_share, sustained_sticks, zone_stick_slip

FS = 100e3
N = 4000
T = np.arange(N) / FS
F0 = 13.31e3  # off the Welch bins (fs / 4096 = 24.4 Hz)
PERIOD = FS / F0  # 7.5 samples


def _periodic():
    """A limit cycle of any wave shape: the fundamental and four harmonics (1/k amplitudes, random phases)."""
    rng = np.random.default_rng(1)
    return sum(np.sin(2 * np.pi * k * F0 * T + rng.uniform(0, 2 * np.pi)) / k for k in range(1, 4))


def _tones(amplitudes=(1.0, 1.0, 1.0), freqs=(13.31e3, 7.13e3, 17.93e3)):
    """Incommensurate tones (no one near another's harmonic); of equal power by default: harmonic share 1/3."""
    return sum(a * np.sin(2 * np.pi * f * T + 0.3 * i) for i, (a, f) in enumerate(zip(amplitudes, freqs)))


def _cycle_stick(n_nodes=60, share=0.3):
    """A harmonic limit cycle's stick: every node sticks for ``share`` of each period, the phase travelling along
    the contact (the stick within each cycle of a vibration faster than the sliding)."""
    phase = (T[:, None] * F0 + np.arange(n_nodes)[None, :] / n_nodes) % 1.0
    return phase < share


def _zone_stick(n_nodes=60, periods=3.0):
    """Within-cycle stick plus a stick zone: ten neighbouring nodes held for ``periods`` periods each, one after
    the other along the contact (a zone travelling with the rotation), each released inside the record."""
    b = _cycle_stick(n_nodes)
    for j in range(10, 20):
        start, length = 2000 + 40 * (j - 10), int(np.ceil(periods * PERIOD))
        b[start - 8:start + length + 8, j] = False  # slipping either side of the hold
        b[start:start + length, j] = True
    return b


def test_harmonic_share_of_a_periodic_record_is_one():
    f0, share = harmonic_share(_periodic(), FS)
    assert f0 == pytest.approx(F0, abs=FS / 4096)
    assert share > 1 - 1e-3  # the Hann window's leakage outside its main lobe: ~5e-4 of a tone's power


@pytest.mark.parametrize("amplitudes, expected", [((1.0, 0.5, 0.5), 1 / 1.5), ((1.0, 1.0, 1.0), 1 / 3),
                                                  ((1.0, 0.1, 0.1), 1 / 1.02)])
def test_harmonic_share_of_incommensurate_tones_in_closed_form(amplitudes, expected):
    """The dominant tone's power over the total: a^2 / sum a_i^2 (equal tones: any of them dominant)."""
    _, share = harmonic_share(_tones(amplitudes), FS)
    assert share == pytest.approx(expected, abs=2e-3)


def test_stick_within_each_cycle_is_not_a_sustained_stick():
    out = sustained_sticks(_cycle_stick(), PERIOD)
    assert out["count"] == 0 and out["nodes"] == 0
    assert out["longest"] == pytest.approx(0.3, abs=1 / PERIOD)  # 30 % of a period, to one sample


def test_a_travelling_stick_zone_is_counted_node_by_node():
    out = sustained_sticks(_zone_stick(periods=3.0), PERIOD)
    assert out["count"] == 10 and out["nodes"] == 10
    assert out["longest"] == pytest.approx(3.0, abs=1 / PERIOD)


def test_a_stick_that_never_releases_is_no_passage():
    """A node stuck to the end of the record (a contact still winding up) has no stick -> slip passage."""
    b = _cycle_stick()
    b[3000:, 5] = True
    assert sustained_sticks(b, PERIOD)["count"] == 0


@pytest.mark.parametrize("response, stick, expected", [
    (_periodic, _cycle_stick, False),  # mode coupling: harmonic, stick only within each cycle
    (_periodic, _zone_stick, False),  # a stick zone, but the vibration stays one harmonic mode
    (_tones, _cycle_stick, False),  # several modes, but no stick zone
    (_tones, _zone_stick, True),  # the paper's stick-slip: a releasing stick zone and a multi-modal response
])
def test_zone_stick_slip_needs_both_marks(response, stick, expected):
    out = zone_stick_slip(response(), FS, stick())
    assert out["stick_slip"] is expected
    assert (out["harmonic_share"] < HARMONIC_SHARE) is (response is _tones)
    assert (out["sustained_sticks"] > 0) is (stick is _zone_stick)


@pytest.mark.parametrize("envelope, rate, marks, expected", [
    ("mode_coupling", 2400.0, (_tones, _zone_stick), "stick_slip"),
    ("mode_coupling", 2400.0, (_periodic, _cycle_stick), "mode_coupling"),
    ("stick_slip", 2400.0, (_periodic, _cycle_stick), "mode_coupling"),  # gross stick, growing envelope
    ("stick_slip", 10.0, (_periodic, _cycle_stick), "stable"),  # gross stick, no significant growth
    ("stable", float("nan"), (_periodic, _cycle_stick), "stable"),
])
def test_ring_regime_follows_the_papers_marks(envelope, rate, marks, expected):
    """The ring kind's regime: the paper's stick-slip replaces the envelope/gross-stick label, which stays as
    ``regime_transient``."""
    from fivid.study.kinds.ring import _paper_regime

    response, stick = marks
    run = xr.Dataset({"acceleration": (("time", "sensor"), response()[:, None])})
    data = {"regime": ((), np.array(envelope, dtype=object), {"long_name": "regime"}),
            "growth_rate": ((), rate, {}), "growth_rate_stderr": ((), 100.0, {})}
    _paper_regime(run, stick(), FS, data)
    assert str(data["regime"][1]) == expected and str(data["regime_transient"][1]) == envelope
