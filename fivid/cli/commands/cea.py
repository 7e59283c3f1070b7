"""``fivid cea MODEL.yaml [--load Q] --mu START STOP STEPS [--prestress] [--json]``: complex eigenvalue analysis against friction."""

from __future__ import annotations

import sys

from fivid.cli import quantity

__all__ = ["register"]

_DESCRIPTION = (
    "Complex eigenvalue analysis of a model config with frictional contact: linearise about steady sliding "
    "under the normal load --load (penalty contact springs and friction coupling at the slave nodes closed under "
    "it by a static preload solve -> non-symmetric stiffness), project on a modal basis and sweep "
    "the friction coefficient. Per mode: frequency and real part of the eigenvalue against mu, and the critical mu "
    "at which the real part crosses zero (null if stable over the range)."
)


def register(subparsers) -> None:
    """Add the ``cea`` sub-command."""
    help_ = "complex eigenvalue analysis: mode-coupling instability against the friction coefficient"
    p = subparsers.add_parser("cea", help=help_, description=_DESCRIPTION)
    p.add_argument("model", metavar="MODEL.yaml",
                   help="model config with a contact pair and a base motion, or the name of a built-in model "
                        "such as triboair_coarse")
    p.add_argument("--load", metavar="Q", type=quantity("N", positive=True),
                   help="normal load, e.g. '5 N' (a bare number is in N; the preload the contact is linearised "
                        "about); leave it "
                        "out for a model pressed by its own pressure loads or an expanding rigid circle (e.g. "
                        "configs/models/ring.yaml)")
    p.add_argument("--mu", nargs=3, required=True, metavar=("START", "STOP", "STEPS"),
                   help="friction coefficients: STEPS values from START to STOP inclusive")
    p.add_argument("-n", "--n-modes", type=int, default=20, metavar="N", help="modes reported (default 20)")
    p.add_argument("--basis", type=int, default=None, metavar="B",
                   help="modal basis size (default max(3N, 40))")
    p.add_argument("--no-damping", action="store_true", help="leave out Rayleigh damping and dashpots")
    p.add_argument("--prestress", action="store_true",
                   help="linearise about the prestressed state: add the initial-stress (geometric) stiffness of the "
                        "preload's static state (fivid.fe.prestress; on by default for a model with 'prestress: true')")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.add_argument("-o", "--output", metavar="CEA.nc", help="write the sweep to netCDF")
    p.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    p.set_defaults(func=run)


def _mu_grid(values):
    import numpy as np

    from fivid.errors import ConfigError

    try:
        start, stop = float(values[0]), float(values[1])
        steps = int(values[2])
    except ValueError:
        raise ConfigError(f"--mu takes START STOP STEPS (two numbers and an integer), got {' '.join(values)}") from None
    if not (np.isfinite(start) and np.isfinite(stop)) or start < 0 or stop <= start or steps < 2:
        raise ConfigError(f"--mu needs 0 <= START < STOP and STEPS >= 2, got {start} {stop} {steps}")
    return np.linspace(start, stop, steps)


def run(args) -> int:
    """Handler of ``fivid cea``."""
    from fivid.errors import ConfigError
    from fivid.fe import load_model
    from fivid.execution.resources import check_modal_memory
    from fivid.fe.cea import Linearisation, cea_to_json, complex_eigenvalue_analysis
    from fivid.fe.static import pressed_by_itself
    from fivid.storage import check_writable, dumps_json, write_netcdf

    mu = _mu_grid(args.mu)
    if args.n_modes < 1:
        raise ConfigError(f"-n must be >= 1, got {args.n_modes}")
    if args.basis is not None and args.basis < args.n_modes:
        raise ConfigError(f"--basis ({args.basis}) must be >= -n ({args.n_modes})")
    if args.output:
        check_writable(args.output, overwrite=args.overwrite)
    load = None if args.load is None else float(args.load)
    check_modal_memory(args.model, args.basis or max(3 * args.n_modes, 40))  # before the mesh is built
    model = load_model(args.model)
    if load is None and not pressed_by_itself(model):
        raise ConfigError("--load Q is needed (e.g. --load '5 N'): the contact is linearised about the nodes closed "
                          "under that normal load (only a model pressed by its own pressure loads or an expanding "
                          "rigid circle can go without)")
    from tqdm import tqdm

    # a bar on a terminal only (disable=None): scripted --json runs keep a clean stderr
    with tqdm(total=mu.size, desc="CEA mu sweep", unit="mu", disable=None, file=sys.stderr) as bar:
        ds = complex_eigenvalue_analysis(
            model, mu, normal_load=load, n_modes=args.n_modes, n_basis=args.basis, progress=bar.update,
            linearisation=Linearisation(damping=not args.no_damping, prestress=True if args.prestress else None))
    if args.output:
        write_netcdf(ds, args.output, overwrite=args.overwrite)
    result = cea_to_json(ds)
    if args.json:
        print(dumps_json(result))
        return 0
    print(f"{model.describe()}; modal basis {result['n_basis']}; mu {mu[0]:g}..{mu[-1]:g} ({mu.size} steps); "
          f"contact closed under {f'{load:g} N' if load is not None else 'the pressure loads'} at "
          f"{len(result['closed_slave_nodes'])} slave node(s)")
    print(" mode  f(mu0) [Hz]  f(mu1) [Hz]  max Re [s-1]  critical mu  partner")
    for m in result["modes"]:
        crit = "-" if m["critical_mu"] is None else f"{m['critical_mu']:.4f}"
        part = "-" if m["partner"] is None else str(m["partner"])
        print(f"{m['mode']:5d} {m['frequency_hz'][0]:12.1f} {m['frequency_hz'][-1]:12.1f} "
              f"{max(m['real_part']):13.2f}  {crit:>11}  {part:>7}")
    if not result["unstable"]:
        print("no mode is unstable over the range", file=sys.stderr)
    return 0
