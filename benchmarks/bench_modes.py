"""Benchmark of fivid.fe modal analysis and CEA; prints one JSON line.

    python benchmarks/bench_modes.py [--quick]

Measured in the same run:
* ``modes_s``: the first 30 modes of the default model (configs/models/triboair.yaml; --quick: the coarse
  variant) by shift-invert Lanczos, against ``lu_s``, one sparse LU of ``K - sigma M`` (the unavoidable core of
  shift-invert): ``modes_over_lu`` says how many factorisation-equivalents the whole modal analysis costs.
* ``cea_s``: a 51-point μ sweep (0..1) on the modal basis (20 modes reported, 60 modes plus the contact-load
  static responses), assembly and basis included, against the full-order
  alternative: one shift-invert Arnoldi of the non-symmetric state-space pencil at a single μ
  (``full_order_point_s``), times 51. ``cea_speedup`` = 51 * full_order_point_s / cea_s.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
from _load_guard import parse_guarded  # noqa: E402  (benchmarks/, this script's folder)


def _full_order_point(model, mu, n_eig, normal_load):
    """Lowest ``n_eig`` eigenvalues of the full state-space system at one μ (shift-invert ARPACK), linearised about
    the same preloaded contact state as the CEA (slave nodes closed under ``normal_load`` [N])."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    from fivid.fe.assembly import damping_matrix, stiffness_matrix
    from fivid.fe.contact import linearise_preloaded_contact
    from fivid.fe.modal import constrained_matrices

    contact, _ = linearise_preloaded_contact(model, normal_load)
    K, M, free = constrained_matrices(model, include_contact=True, contact=contact)
    Kf = contact.friction_stiffness_matrix()[free][:, free]
    C = damping_matrix(model, mass="consistent", stiffness=stiffness_matrix(model))[free][:, free]
    n = K.shape[0]
    eye = sp.identity(n, format="csr")
    A = sp.bmat([[None, eye], [-(K + mu * Kf), -C]], format="csc")
    B = sp.bmat([[eye, None], [None, M]], format="csc")
    lam = spla.eigs(A, k=2 * n_eig, M=B, sigma=0.0, which="LM", return_eigenvectors=False)
    return lam


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="coarse model (fast)")
    parser.add_argument("--normal-load", type=float, default=5.0, metavar="N",
                        help="normal load [N] of the preload the CEA linearises about (default 5, the sample runs')")
    args, load = parse_guarded(parser, argv)

    import scipy.linalg  # noqa: F401  (imports outside the timed regions)
    import scipy.sparse.linalg as spla
    import threadpoolctl  # noqa: F401
    import xarray

    from fivid.fe import load_model
    from fivid.fe.cea import complex_eigenvalue_analysis
    from fivid.fe.modal import _default_shift, constrained_matrices, modal_analysis

    xarray.Dataset({"warm_up": ("x", [0.0])})  # xarray loads its duck-array modules on the first Dataset
    name = "triboair_coarse" if args.quick else "triboair"
    model = load_model(ROOT / "configs" / "models" / f"{name}.yaml")

    K, M, _ = constrained_matrices(model)
    sigma = _default_shift(K, M)
    t = time.perf_counter()
    spla.splu((K - sigma * M).tocsc())
    lu_s = time.perf_counter() - t

    t = time.perf_counter()
    modal_analysis(model, 30)
    modes_s = time.perf_counter() - t

    mu = np.linspace(0.0, 1.0, 51)
    t = time.perf_counter()
    ds = complex_eigenvalue_analysis(model, mu, normal_load=args.normal_load, n_modes=20, n_basis=60)
    cea_s = time.perf_counter() - t

    t = time.perf_counter()
    _full_order_point(model, 0.5, 20, args.normal_load)
    full_s = time.perf_counter() - t

    print(json.dumps({
        "benchmark": "bench_modes",
        "model": name,
        "n_dofs": model.n_dofs,
        "normal_load_n": args.normal_load,
        "modes": 30,
        "modes_s": round(modes_s, 4),
        "lu_s": round(lu_s, 4),
        "modes_over_lu": round(modes_s / lu_s, 2),
        "cea_points": int(mu.size),
        "cea_s": round(cea_s, 4),
        "cea_unstable_modes": int(np.isfinite(ds["critical_mu"].values).sum()),
        "full_order_point_s": round(full_s, 4),
        "cea_speedup": round(mu.size * full_s / cea_s, 2),
        "load_average_1min": load,
    }))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
