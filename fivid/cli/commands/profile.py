"""``fivid profile FILE [--window A B] [--form F] [--cutoff Q] [--short-cutoff Q] [--contact-law [YAML]] [--json]
[-o OUT.nc] [--plot PNG]``."""

from __future__ import annotations

import sys

from fivid.cli import quantity

__all__ = ["register"]

_DESCRIPTION = """\
Roughness parameters of a stylus profile (ISO 4287 / ISO 21920-2, DIN 4768), computed as a
profilometer does between its cursors: the evaluation window is cut out, a least-squares line
(or polynomial) is removed over it, optionally the ISO 16610-21 Gaussian filter separates
roughness from waviness (cut-off --cutoff, short-wave --short-cutoff), and Ra, Rq, Rz, RzDIN, Rt,
Rp, Rv, Rsk, Rku, Rsm, Rdq (RΔq), the mean attack angle and, with a cut-off, Wa and Wq are
computed, in SI units (m; Rsk, Rku dimensionless; Rdq and angles in rad).

Files: Dektak CSV exports, text files with a header 'x [unit],z [unit]', and ISO 25178-72 .x3p
files (needs 'pip install x3pio'). For a Dektak export the instrument's own results are printed
beside fivid's, and its cursor window is the default window.

--contact-law adds the Greenwood-Williamson parameters of the evaluated roughness (summit height
deviation, summit radius, summit density from the profile's spectral moments m0, m2, m4, McCool
1986, for an isotropic Gaussian surface) as the 'normal:' block of a model config's contact; with
a file name it writes that block there (YAML). Filter the stylus noise first (--short-cutoff).

Lengths are quantities with a unit: --window '468 um' '733 um', --cutoff '80 um'.
See docs/surface.md."""

_EPILOG = """\
example:
  fivid profile dektak-1.csv --window '468 um' '733 um' --json
  fivid profile trace.csv --cutoff '0.8 mm' --short-cutoff '2.5 um' -o trace.nc --plot trace.png
  fivid profile trace.csv --short-cutoff '2.5 um' --contact-law gw.yaml"""


# a bare number is refused: profiles are read in um, and '468' as metres is a slip, not SI
_LENGTH = quantity("m", bare_numbers=False)
_POSITIVE_LENGTH = quantity("m", bare_numbers=False, positive=True)


def register(subparsers) -> None:
    """Add the ``profile`` sub-command."""
    import argparse

    p = subparsers.add_parser(
        "profile", help="roughness parameters of a surface profile (Dektak CSV, x/z text, X3P)",
        description=_DESCRIPTION, epilog=_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("file", metavar="FILE", help="profile file: Dektak .csv export, 'x [um],z [um]' .csv/.txt, .x3p")
    p.add_argument("--window", nargs=2, metavar=("START", "END"), type=_LENGTH,
                   help="evaluation window, both ends included, as lengths with units, e.g. '468 um' '733 um' "
                        "(default: the instrument's cursor window when the file has one, else the whole profile)")
    p.add_argument("--form", default="line", metavar="FORM",
                   help="form removed by least squares over the window: line (default), poly:N or none")
    p.add_argument("--cutoff", metavar="Q", type=_POSITIVE_LENGTH,
                   help="cut-off wavelength λc of the Gaussian roughness filter, e.g. '0.8 mm' (default: no filter; "
                        "R parameters of the primary profile)")
    p.add_argument("--short-cutoff", metavar="Q", type=_POSITIVE_LENGTH,
                   help="cut-off λs of the Gaussian short-wave filter, e.g. '2.5 um'")
    p.add_argument("--ends", choices=("trim", "keep"), default="trim",
                   help="with --cutoff: drop λc/2 at each end of the window (trim, default) or keep them")
    p.add_argument("--contact-law", nargs="?", const="-", metavar="YAML",
                   help="Greenwood-Williamson parameters of the roughness (McCool's spectral moments): printed, "
                        "or written as a model config's contact 'normal:' block to YAML")
    p.add_argument("--json", action="store_true",
                   help='print {"Ra": ..., "Rq": ..., ...} in SI units, with the instrument\'s values and settings')
    p.add_argument("-o", "--output", metavar="OUT.nc", help="write the profile, roughness and parameters to netCDF")
    p.add_argument("--overwrite", action="store_true", help="replace existing output files")
    p.add_argument("--plot", metavar="PNG", help="write a figure of the profile, roughness and PSD to this PNG")
    p.set_defaults(func=run)


def _summary(profile, ev) -> dict:
    from fivid.surface import PARAMETER_UNITS, instrument_results

    out = dict(ev.parameters)
    out["units"] = {k: PARAMETER_UNITS[k] for k in ev.parameters}
    ins = instrument_results(profile)
    if ins:
        out["instrument"] = ins
        out["relative_difference"] = {k: ev.parameters[k] / v - 1.0 for k, v in ins.items()
                                      if k in ev.parameters and v != 0}
    out["settings"] = ev.settings
    out["source"] = profile.attrs.get("source")
    return out


def run(args) -> int:
    """Handler of ``fivid profile``."""
    from fivid.storage import check_writable, dumps_json
    from fivid.surface import evaluate_profile, read_profile

    law_file = args.contact_law if args.contact_law not in (None, "-") else None
    for path in (args.output, args.plot, law_file):
        if path:
            check_writable(path, overwrite=args.overwrite)
    window = None if args.window is None else tuple(float(v) for v in args.window)
    cutoff = None if args.cutoff is None else float(args.cutoff)
    short = None if args.short_cutoff is None else float(args.short_cutoff)
    profile = read_profile(args.file)
    if window is None and "instrument_window_start" in profile.attrs:
        window = (profile.attrs["instrument_window_start"], profile.attrs["instrument_window_end"])
    ev = evaluate_profile(profile, window=window, form=args.form, cutoff=cutoff, short_cutoff=short, ends=args.ends)
    summary = _summary(profile, ev)
    if args.contact_law is not None:
        summary["contact_law"] = _contact_law(ev, profile, law_file, args.overwrite)
    if args.output:
        from fivid.surface.output import write_evaluation

        write_evaluation(profile, ev, args.output, overwrite=args.overwrite)
        summary["output"] = str(args.output)
    if args.plot:
        from fivid.surface.figures import plot_evaluation

        plot_evaluation(profile, ev, args.plot)
        summary["plot"] = str(args.plot)
    if args.json:
        print(dumps_json(summary))
    else:
        _print_table(summary)
    return 0


def _contact_law(ev, profile, path, overwrite: bool) -> dict:
    """GW parameters of the evaluated roughness (:func:`fivid.surface.contact_law.gw_parameters`), the model
    config block, and the YAML file written when ``path`` is given."""
    import yaml

    from fivid.storage import write_text
    from fivid.surface.contact_law import gw_config, gw_parameters

    gw = gw_parameters(ev.roughness, float(ev.settings["step"]))
    out = {**gw, "normal": gw_config(gw), "method": "McCool 1986 spectral moments (isotropic Gaussian surface)",
           "units": {"sigma": "m", "asperity_radius": "m", "asperity_density": "m-2", "alpha": "1",
                     "mean_summit_height": "m", "rq": "m", "m0": "m2", "m2": "1", "m4": "m-2"}}
    rsk, rku = ev.parameters.get("Rsk"), ev.parameters.get("Rku")
    if rsk is not None and rku is not None and (abs(rsk) > 0.5 or abs(rku - 3.0) > 1.0):
        out["warning"] = (f"the heights are not Gaussian (Rsk {rsk:.3g}, Rku {rku:.3g}; Gaussian: 0, 3): the "
                          "estimator assumes a Gaussian surface, read the parameters as indicative")
    if path:
        s = ev.settings
        head = (f"# Greenwood-Williamson surface of {profile.attrs.get('source')} (fivid profile --contact-law): "
                f"window [{s['window_start']:.6g}, {s['window_end']:.6g}] m, form {s['form']}, cut-offs "
                f"{s['cutoff']} / {s.get('short_cutoff')} m; McCool 1986 spectral moments, alpha {gw['alpha']:.3g}\n")
        write_text(path, head + yaml.safe_dump({"normal": out["normal"]}, sort_keys=False), overwrite=overwrite)
        out["file"] = str(path)
    return out


def _print_table(summary) -> None:
    s = summary["settings"]
    print(f"{summary['source']}: window [{s['window_start'] * 1e6:.6g}, {s['window_end'] * 1e6:.6g}] um, "
          f"{s['n_points']} points, form {s['form']}, cut-off "
          f"{'none' if s['cutoff'] is None else format(s['cutoff'] * 1e6, '.6g') + ' um'}")
    ins = summary.get("instrument", {})
    print(f"{'symbol':>12}  {'value':>14}  {'unit':>4}  {'instrument':>14}  {'difference':>10}")
    for k, unit in summary["units"].items():
        v = summary[k]
        other = f"{ins[k]:14.6g}  {summary['relative_difference'][k]:+10.2%}" if k in summary.get(
            "relative_difference", {}) else ""
        print(f"{k:>12}  {v:14.6g}  {unit:>4}  {other}")
    law = summary.get("contact_law")
    if law:
        print(f"Greenwood-Williamson surface (McCool 1986 spectral moments; alpha = m0 m4 / m2^2 = {law['alpha']:.4g}):")
        for k, unit in (("sigma", "m"), ("asperity_radius", "m"), ("asperity_density", "m-2"),
                        ("mean_summit_height", "m")):
            print(f"{k:>20}  {law[k]:14.6g}  {unit}")
        print("model config block:  normal: {" + ", ".join(f"{k}: {v}" for k, v in law["normal"].items()) + "}")
        if "warning" in law:
            print(f"warning: {law['warning']}", file=sys.stderr)
        if "file" in law:
            print(f"contact law written to {law['file']}", file=sys.stderr)
    for key in ("output", "plot"):
        if key in summary:
            print(f"{key} written to {summary[key]}", file=sys.stderr)
