"""``fivid law show LAW.nc`` and ``fivid law eval LAW.nc --velocity Q --roughness Q``: read an identified law."""

from __future__ import annotations

import argparse

__all__ = ["register"]

_DESCRIPTION = """\
Read a friction-law file written by 'fivid identify'.
  show   the amplitude form, its coefficients with units and 95 % intervals, the identified domain,
         the candidate-form selection table (AICc, Akaike weight, cross-validation error) and whether
         the spectral shape depends on the condition
  eval   the predicted amplitude A (RMS of mu_p in the band) at a condition, with its 95 % prediction
         interval; outside the identified domain a warning names the variable and the identified range
         (--strict: an error, exit 2). See docs/identification.md."""

_EPILOG = """\
examples:
  fivid law show law.nc
  fivid law eval law.nc --velocity "7.5 mm/s" --roughness "1 um" --load "5 N" --json

exit status: 0 ok; 2 bad input, or a condition outside the domain with --strict; 1 unexpected."""


def register(subparsers) -> None:
    """Add the ``law`` sub-command with ``show`` and ``eval``."""
    from fivid.cli import quantity

    p = subparsers.add_parser("law", help="show an identified friction law or evaluate its amplitude",
                              description=_DESCRIPTION, epilog=_EPILOG,
                              formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="law_command", metavar="ACTION", required=True)
    show = sub.add_parser("show", help="forms, coefficients with units and CIs, domain, selection table")
    show.add_argument("law_path", metavar="LAW.nc", help="law file written by 'fivid identify'")
    show.add_argument("--json", action="store_true", help="print JSON instead of text")
    show.set_defaults(func=_show)
    ev = sub.add_parser("eval", help="predicted amplitude with its 95 %% prediction interval at a condition")
    ev.add_argument("law_path", metavar="LAW.nc", help="law file written by 'fivid identify'")
    ev.add_argument("--velocity", required=True, metavar="Q", type=quantity("m s-1", nonnegative=True),
                    help="sliding velocity, e.g. '7.5 mm/s' (a bare number is in m/s)")
    ev.add_argument("--roughness", required=True, metavar="Q", type=quantity("m", nonnegative=True),
                    help="roughness Ra, e.g. '1 um' (a bare number is in m)")
    ev.add_argument("--load", metavar="Q", type=quantity("N", positive=True),
                    help="normal load, e.g. '5 N' (a bare number is in N; needed when the law uses it)")
    ev.add_argument("--confidence", type=float, default=0.95, help="level of the interval (default 0.95)")
    ev.add_argument("--strict", action="store_true", help="refuse a condition outside the identified domain (exit 2)")
    ev.add_argument("--json", action="store_true", help="print JSON instead of text")
    ev.set_defaults(func=_eval)


def law_summary(ds, law, domain) -> dict:
    """The content ``fivid law show`` prints (plain Python)."""
    from fivid.friction import coefficient_units

    out = {"law": ds.attrs.get("law"), "law_file_version": int(ds.attrs.get("law_file_version", 0)),
           "mu0": float(law.mu0), "mu0_ci": [ds["mu0"].attrs.get("ci_lower"), ds["mu0"].attrs.get("ci_upper")],
           "law_sha256": law.sha256}
    if out["law"] != "perturbed_coulomb":
        return out
    m = law.amplitude_model
    lower = ds["amplitude_ci_lower"].values if "amplitude_ci_lower" in ds else [None] * len(m.names)
    upper = ds["amplitude_ci_upper"].values if "amplitude_ci_upper" in ds else [None] * len(m.names)
    out["band"] = list(law.band)
    out["amplitude_form"] = m.form
    out["terms"] = list(m.terms)
    out["coefficients"] = [{"name": n, "value": float(c), "units": coefficient_units(n), "stderr": float(s),
                            "ci95": [_f(lo), _f(hi)]}
                           for n, c, s, lo, hi in zip(m.names, m.coefficients, m.stderr, lower, upper)]
    out["residual_variance"] = _f(m.residual_variance)
    out["prediction_interval"] = ("available" if out["residual_variance"] is not None else
                                  "not available (no residual variance in this file): eval gives the mean's interval")
    out["domain"] = None if domain is None else dict(domain.to_json(), description=domain.describe())
    out["selection_rule"] = ds.attrs.get("selection_rule")
    out["selection_why"] = ds.attrs.get("selection_why")
    table = []
    if "form" in ds.dims:
        for i in range(ds.sizes["form"]):
            row = {"form": str(ds["form"].values[i])}
            for name in ("form_fitted", "form_chosen", "form_n_params", "form_aicc", "form_delta_aicc",
                         "form_akaike_weight", "form_cv_error", "form_aic", "form_bic", "form_reason"):
                if name in ds:
                    v = ds[name].values[i]
                    row[name[5:]] = v if isinstance(v, str) else _f(v)
            table.append(row)
    out["selection_table"] = table
    out["shape_dependence"] = str(ds.attrs.get("shape_dependence", "one shape (not tested: law file version 1)"))
    out["shape_test"] = {k[len("shape_test_"):]: _plain(v) for k, v in ds.attrs.items() if k.startswith("shape_test_")}
    if "run" in ds.dims and "run_cooks_distance" in ds:
        out["influential_runs"] = [str(r) for r, k in zip(ds["run"].values, ds["run_influential"].values) if k]
    return out


def _f(x):
    import numpy as np

    if x is None:
        return None
    x = float(x)
    return x if np.isfinite(x) else None


def _plain(v):
    return v.item() if hasattr(v, "item") else v


def _show(args) -> int:
    from fivid.cli.law_domain import open_law_file
    from fivid.storage import dumps_json

    ds, law, domain = open_law_file(args.law_path)
    info = law_summary(ds, law, domain)
    if args.json:
        print(dumps_json(info))
        return 0
    lines = [f"{args.law_path}: {info['law']} friction law (file version {info['law_file_version']})",
             f"mu0 = {info['mu0']:.5f}" + (f"  (95 % CI {info['mu0_ci'][0]:.5f} .. {info['mu0_ci'][1]:.5f})"
                                           if info["mu0_ci"][0] is not None else "")]
    if info["law"] == "perturbed_coulomb":
        lines.append(f"band {info['band'][0]:g}-{info['band'][1]:g} Hz; amplitude (RMS of mu_p) form "
                     f"{info['amplitude_form']}, factors: {', '.join(info['terms']) or 'none'}")
        lines.append(f"  {'coefficient':28s} {'value':>12s} {'units':>8s} {'stderr':>10s}   95 % CI")
        for c in info["coefficients"]:
            ci = ("-" if c["ci95"][0] is None else f"{c['ci95'][0]:.4g} .. {c['ci95'][1]:.4g}")
            lines.append(f"  {c['name']:28s} {c['value']:12.5g} {c['units']:>8s} {c['stderr']:10.3g}   {ci}")
        lines.append(f"prediction interval: {info['prediction_interval']}")
        lines.append("domain: " + (info["domain"]["description"] if info["domain"] else "not recorded"))
        if info["selection_table"]:
            lines.append(f"selection: {info['selection_rule']}")
            if info["selection_why"]:
                lines.append(f"  {info['selection_why']}")
            lines.append(f"  {'form':28s} {'AICc':>9s} {'dAICc':>7s} {'weight':>7s} {'CV error':>9s}")
            for r in info["selection_table"]:
                if not r.get("fitted", 1):
                    lines.append(f"  {r['form']:28s} not fitted: {r.get('reason', '')}")
                    continue
                lines.append(f"  {r['form']:28s} {_g(r.get('aicc'), '9.2f')} {_g(r.get('delta_aicc'), '7.2f')} "
                             f"{_g(r.get('akaike_weight'), '7.3f')} {_g(r.get('cv_error'), '9.3g')}"
                             + ("  <- chosen" if r.get("chosen") else ""))
        test = info["shape_test"]
        lines.append(f"spectral shape: {info['shape_dependence']}"
                     + (f" (test: {test.get('statistic', '')}, p = {test['p_value']:.3g})"
                        if isinstance(test.get("p_value"), float) else ""))
        if info.get("influential_runs"):
            lines.append(f"influential runs (Cook's distance > 4/n, kept): {', '.join(info['influential_runs'])}")
    print("\n".join(lines))
    return 0


def _g(x, spec):
    return format("-", f">{spec.split('.')[0] or 1}") if x is None else format(x, spec)


def _eval(args) -> int:
    import numpy as np

    from fivid.cli.law_domain import check_law_condition, open_law_file
    from fivid.errors import FividError
    from fivid.storage import dumps_json

    v, ra = float(args.velocity), float(args.roughness)
    fn = float(args.load) if args.load is not None else None
    ds, law, domain = open_law_file(args.law_path)
    if not 0 < args.confidence < 1:
        raise FividError(f"--confidence {args.confidence!r}; it must be in (0, 1)")
    if ds.attrs.get("law") != "perturbed_coulomb":
        raise FividError(f"{args.law_path}: a {ds.attrs.get('law')} law has no amplitude to evaluate")
    m = law.amplitude_model
    if fn is None and ("normal_load" in m.terms or m.form in ("power_law_load", "linear_velocity_load")):
        raise FividError(f"{args.law_path}: the amplitude law depends on the normal load: pass --load (e.g. '5 N')")
    pred = check_law_condition(law, domain, v, ra, fn, strict=args.strict, confidence=args.confidence)
    out = {"law": str(args.law_path), "amplitude_form": m.form, "sliding_velocity": v, "roughness_ra": ra,
           "normal_load": fn, "amplitude": float(pred.amplitude[0]), "lower": float(pred.lower[0]),
           "upper": float(pred.upper[0]), "confidence": pred.confidence, "interval": pred.kind,
           "inside_domain": bool(pred.inside[0]), "warnings": pred.messages}
    if args.json:
        print(dumps_json(out))
    else:
        where = f"V {v * 1e3:.4g} mm/s, Ra {ra * 1e6:.4g} um" + ("" if fn is None else f", Fn {fn:.4g} N")
        print(f"A = {out['amplitude']:.5g}  ({pred.confidence:.0%} {pred.kind} interval "
              f"{out['lower']:.5g} .. {out['upper']:.5g}) at {where}"
              + ("" if out["inside_domain"] else "  [outside the identified domain]"))
    return 0 if np.isfinite(out["amplitude"]) else 2
