"""``fivid modes MODEL.yaml [-n N] [--load Q | --contact] [--prestress] [--json] [-o MODES.nc]``: natural frequencies and mode
shapes of a model."""

from __future__ import annotations

import sys

from fivid.cli import quantity

__all__ = ["register"]


def register(subparsers) -> None:
    """Add the ``modes`` sub-command."""
    p = subparsers.add_parser(
        "modes",
        help="natural frequencies and mode shapes of a model config (sparse shift-invert)",
        description="Modal analysis of a finite-element model config (configs/models/*.yaml): the lowest N "
        "natural frequencies with clamps and imposed motions eliminated, by shift-invert Lanczos. "
        "With --load the bodies are coupled at the contact nodes closed under that normal load (static preload "
        "solve): the linearisation about the sliding equilibrium. Mode shapes can be written to netCDF.",
    )
    p.add_argument("model", metavar="MODEL.yaml",
                   help="model config (see docs/model-config.md), or the name of a built-in model such as "
                        "triboair_coarse (configs/models/, shipped with fivid)")
    p.add_argument("-n", "--n-modes", type=int, default=30, metavar="N", help="number of modes (default 30)")
    p.add_argument("--json", action="store_true", help='print {"frequencies_hz": [...], ...} as JSON')
    p.add_argument("-o", "--output", metavar="MODES.nc", help="write frequencies and mode shapes to netCDF")
    p.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    p.add_argument("--mass", choices=("consistent", "lumped"), default="consistent",
                   help="mass matrix (default consistent; lumped is what the explicit solver uses)")
    p.add_argument("--load", metavar="Q", type=quantity("N", positive=True),
                   help="normal load, e.g. '5 N' (a bare number is in N): couple the bodies by normal penalty "
                        "springs at the slave "
                        "nodes closed under it (static preload solve; no friction)")
    p.add_argument("--contact", action="store_true",
                   help="couple the bodies at the contact: with --load, under that normal load; without, under the "
                        "model's own loading (pressure loads, an expanding rigid circle: e.g. the ring of seed 002)")
    p.add_argument("--prestress", action="store_true",
                   help="vibrations about the prestressed state: add the initial-stress (geometric) stiffness of the "
                        "static state (the contact preload with --load/--contact, else the pressure loads); "
                        "tension stiffens, compression softens (fivid.fe.prestress; on by default for a model with "
                        "'prestress: true')")
    p.add_argument("--damping-curve", metavar="PNG",
                   help="plot the modal damping ratio vs frequency of the model's damping scheme (classic or "
                        "band-limited Rayleigh, docs/model-config.md) with the modes marked, to this PNG file")
    p.set_defaults(func=run)


def run(args) -> int:
    """Handler of ``fivid modes``."""
    from fivid.errors import ConfigError
    from fivid.fe import load_model
    from fivid.fe.modal import modal_analysis, modes_to_json, write_modes
    from fivid.execution.resources import check_modal_memory
    from fivid.fe.static import pressed_by_itself
    from fivid.storage import check_writable, dumps_json

    if args.n_modes < 1:
        raise ConfigError(f"-n must be >= 1, got {args.n_modes}")
    if args.output:
        check_writable(args.output, overwrite=args.overwrite)
    if args.damping_curve:
        check_writable(args.damping_curve, overwrite=True)
    load = None if args.load is None else float(args.load)
    check_modal_memory(args.model, args.n_modes)  # from the config's divisions, before the mesh is built
    model = load_model(args.model)
    if args.contact and load is None and not pressed_by_itself(model):
        raise ConfigError("--contact needs --load Q (e.g. --load '5 N'): the contact is linearised about the "
                          "nodes closed under that normal load (or pressure loads or an expanding rigid circle in the "
                          "model that press it)")
    include = load is not None or bool(args.contact)
    ds = modal_analysis(model, args.n_modes, mass=args.mass, include_contact=include, normal_load=load,
                        prestress=True if args.prestress else None)
    if args.output:
        write_modes(ds, args.output, overwrite=args.overwrite)
    summary = modes_to_json(ds)
    summary.update(_damping_summary(model, summary["frequencies_hz"]))
    if args.damping_curve:
        _plot_damping_curve(model, summary["frequencies_hz"], args.damping_curve)
        summary["damping_curve"] = str(args.damping_curve)
    if args.output:
        summary["output"] = str(args.output)
    if args.json:
        print(dumps_json(summary))
    else:
        print(f"{model.describe()}; {ds.attrs['n_free_dofs']} free dofs; {args.mass} mass")
        if "contact" in summary:
            what = f"{load:g} N" if load is not None else "the model's own loading"
            print(f"contact closed under {what} at {len(summary['closed_slave_nodes'])} slave node(s)")
            for c in summary["contact"]:
                print(f"  {c['contact']}: {c['normal_law']}; normal force {c['normal_force_n']:.4g} N over "
                      f"{1e3 * c['contact_length_m']:.4g} mm, mean/peak pressure {c['mean_pressure_pa']:.4g}/"
                      f"{c['peak_pressure_pa']:.4g} Pa, normal stiffness {c['normal_stiffness_n_per_m']:.4g} N/m")
        print(f"damping: {summary['damping_scheme']}")
        print(" mode   frequency [Hz]   damping ratio")
        for i, (f, z) in enumerate(zip(summary["frequencies_hz"], summary["damping_ratios"]), 1):
            print(f"{i:5d}   {f:14.2f}   " + (f"{z:13.5f}" if z is not None else f"{'-':>13}"))  # rigid: 0 Hz
        if args.output:
            print(f"mode shapes written to {args.output}", file=sys.stderr)
    return 0


def _damping_summary(model, frequencies) -> dict:
    """The damping scheme and each mode's exact damping ratio under it (``fivid.fe.damping``)."""
    import numpy as np

    from fivid.fe.damping import damping_ratio, scheme_name

    f = np.asarray(frequencies, dtype=float)
    pos = f > 0
    z = np.full(f.shape, np.nan)
    z[pos] = damping_ratio(f[pos], model.rayleigh_alpha, model.rayleigh_beta, model.damping_cutoff)
    return {"damping_scheme": scheme_name(model.rayleigh_beta, model.damping_cutoff),
            "rayleigh_alpha": model.rayleigh_alpha, "rayleigh_beta": model.rayleigh_beta,
            "damping_cutoff_hz": None if not np.isfinite(model.damping_cutoff) else model.damping_cutoff,
            "damping_ratios": [None if not np.isfinite(v) else float(v) for v in z]}


def _plot_damping_curve(model, frequencies, path) -> None:
    """PNG of zeta(f) for the model's scheme (and classic Rayleigh with the same alpha, beta for comparison)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from fivid.fe.damping import damping_ratio, scheme_name
    from fivid.storage import atomic_path

    f_modes = np.asarray([f for f in frequencies if f > 0])
    hi = max(1e5, 3 * f_modes.max()) if f_modes.size else 1e5
    f = np.geomspace(10.0, hi, 400)
    a, b, fc = model.rayleigh_alpha, model.rayleigh_beta, model.damping_cutoff
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.loglog(f, damping_ratio(f, a, b, fc), label=f"{scheme_name(b, fc)} (this model)")
    if np.isfinite(fc):
        ax.loglog(f, damping_ratio(f, a, b), "--", color="0.5", label="classic Rayleigh, same alpha and beta")
        ax.axvline(fc, color="0.7", lw=0.8)
    if f_modes.size:
        ax.loglog(f_modes, damping_ratio(f_modes, a, b, fc), "o", ms=4, label="modes")
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("modal damping ratio [-]")
    ax.set_title(f"damping of {model.config.get('name', 'model')}: alpha {a:.4g} 1/s, beta {b:.4g} s")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=120, bbox_inches="tight")
    plt.close(fig)

