"""The prestress stiffness in the explicit internal force (issue 31 item 2): a transient run and the modal analysis
of a model with ``prestress: true`` describe the same system, ``K + K_sigma`` about the static preload.

Oracle: a steel strip (synthetic, L/h = 50) stretched by an imposed end displacement (uniform ``s_xx = E delta / L``
= 42 MPa, exact for Q4) and set vibrating by a uniform transverse initial velocity. Its mid-span deflection after
the stretch ramp rings at the first bending mode, whose frequency the modal analysis gives for ``K + K_sigma``
(tests/fe/test_fe_prestress.py checks that against the tensioned continuum's closed form: the string's
``s (pi/L)^2 / rho`` added to ``omega_1^2``). The tension raises it by 6.4 %, so the comparison tells the two
systems apart by ~60 times the tolerance."""

import json
import math

import numpy as np
import pytest
import yaml

from fivid.cli import main
from fivid.fe import load_model
from fivid.fe.modal import modal_analysis

E, NU, RHO = 210e9, 0.3, 7850.0
L, H, T = 0.5, 0.01, 0.01  # length, depth, thickness [m]
DELTA, RAMP = 1e-4, 5e-3  # end stretch [m] and its ramp [s]
FS, DURATION = 20e3, 0.2  # output rate [Hz], record [s]


def strip(prestress: bool) -> dict:
    """The stretched strip (100 x 2 elements): x held on the left face, moved by DELTA on the right face, the
    mid-depth nodes of both ends pinned in y; uniform initial y-velocity; a mid-span sensor."""
    def motion(name, edge, component, amplitude=0.0, mid=True, **kw):
        return {"name": name, "body": "s", "edge": edge, **({"y": [H / 2, H / 2]} if mid else {}),
                "component": component, "kind": "displacement", "amplitude": amplitude, **kw}

    return {"name": "strip", "prestress": prestress,
            "bodies": {"s": {"corners": [[0, 0], [L, 0], [L, H], [0, H]], "divisions": [100, 2],
                             "material": {"E": E, "nu": NU, "rho": RHO}, "thickness": T,
                             "initial_velocity": [0.0, 0.05]}},
            "motions": [motion("pin_y", "left", "y"), motion("pin_ry", "right", "y"),
                        motion("hold", "left", "x", mid=False),
                        motion("stretch", "right", "x", DELTA, mid=False, ramp_time=RAMP)],
            "sensors": [{"name": "mid", "body": "s", "at": [L / 2, H / 2], "direction": "y"}]}


def _ringing_frequency(tmp_path, capsys, cfg) -> tuple[float, int, float]:
    """Mean frequency [Hz] of the mid-span deflection after the ramp from its upward zero crossings (linear
    interpolation), their number, and the run's largest energy-balance error [J]."""
    import xarray as xr

    path = tmp_path / f"{cfg['name']}_{cfg['prestress']}.yaml"
    path.write_text(yaml.safe_dump(cfg))
    out = path.with_suffix(".nc")
    assert main(["simulate", str(path), "--duration", f"{DURATION} s", "--sample-rate", f"{FS} Hz", "-o", str(out),
                 "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    # the automatic path runs full: the prestressed strip because the reduced basis has no K_sigma; the plain one,
    # undamped, because its finite error estimate is large (its PSD peaks are the Hann window's own, with nulls)
    assert summary["solver_path"] == "full"
    assert cfg["prestress"] or 0.5 < summary["reduced_error_estimate_db"] < math.inf
    with xr.open_dataset(out) as ds:
        t, y = ds["time"].values, ds["sensor_displacement"].values
    keep = t > RAMP + 1e-3
    t, y = t[keep], y[keep]
    i = np.flatnonzero((y[:-1] < 0) & (y[1:] >= 0))
    tc = t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i])
    return (tc.size - 1) / (tc[-1] - tc[0]), tc.size, summary["max_energy_balance_error_j"]


def test_transient_with_the_prestress_term_rings_at_the_prestressed_modal_frequency(tmp_path, capsys):
    """With ``prestress: true`` the transient's first bending frequency is the K + K_sigma modal one, without it the
    elastic one, each within the record's resolution: the period is read between the first and the last of N
    zero crossings, each located to well within one output sample, so 2 / (fs t_record) (5e-4); plus the third
    mode's shift of those two crossings, (a3 / a1) / (pi N) ~ 3e-4 (uniform initial velocity: a3/a1 ~ 1/(3 x 5.2)
    from the frequencies); the central-difference period error (omega dt)^2 / 24 ~ 1e-8 is far below. Measured:
    1.1e-4 and 1.0e-4. The energy balance stays closed (the prestress term's reference force is booked as load
    work)."""
    results = {}
    for prestress in (True, False):
        model = load_model(strip(prestress))
        f_modal = float(modal_analysis(model, 1)["frequency"].values[0])
        f_run, n, energy_error = _ringing_frequency(tmp_path, capsys, strip(prestress))
        t_record = DURATION - RAMP - 1e-3
        tol = 2.0 / (FS * t_record) + (1.0 / (3 * 5.2)) / (np.pi * n)
        assert f_run == pytest.approx(f_modal, rel=tol), (prestress, f_run, f_modal, tol)
        assert abs(energy_error) < 1e-9
        results[prestress] = (f_modal, tol)
    (f_ps, tol), (f_el, _) = results[True], results[False]
    assert f_ps / f_el - 1 > 20 * tol  # the term matters: tension stiffens by 6.4 %
