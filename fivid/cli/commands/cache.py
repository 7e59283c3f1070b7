"""``fivid cache info|clear [--cache-dir DIR] [--json]``: the on-disk cache of reduced (Craig-Bampton) bases and
static preloads."""

from __future__ import annotations

__all__ = ["register", "run"]


def register(subparsers) -> None:
    """Add the ``cache`` sub-command."""
    p = subparsers.add_parser(
        "cache",
        help="show or clear the cache of reduced-order (Craig-Bampton) bases and static preloads",
        description="fivid builds the reduced basis of a model once and keeps it on disk, keyed by the model's "
        "content (mesh, materials, contact and sensor nodes, damping, cut-off and mass-scaling settings, fivid "
        "version), so that repeated 'fivid simulate' calls, the pipeline, Monte-Carlo envelopes and studies reuse "
        "it; concurrent processes build it once. The static preload (clamp displacement and contact state under a "
        "normal load) is kept beside them (sub-folder preloads/), keyed by the model's content, the load and the "
        "friction coefficient. Location: $FIVID_CACHE_DIR if set, else fivid/bases in the user "
        "cache folder (~/.cache/fivid/bases on Linux); --cache-dir overrides both. 'info' lists the entries, "
        "'clear' removes them (they are rebuilt when needed).",
    )
    p.add_argument("action", choices=("info", "clear"),
                   help="info: list the cached bases and preloads; clear: remove them")
    p.add_argument("--cache-dir", metavar="DIR", help="cache folder (default $FIVID_CACHE_DIR or the user cache)")
    p.add_argument("--json", action="store_true", help="print a JSON summary on stdout")
    p.set_defaults(func=run)


def run(args) -> int:
    """Handler of ``fivid cache``."""
    from fivid.execution.resources import format_bytes
    from fivid.solver.basis_cache import cache_info, clear_cache
    from fivid.storage import dumps_json

    if args.action == "clear":
        n = clear_cache(args.cache_dir)
        info = cache_info(args.cache_dir)
        if args.json:
            print(dumps_json({"folder": info["folder"], "removed": n}))
        else:
            print(f"removed {n} cache entr{'y' if n == 1 else 'ies'} (bases and preloads) from {info['folder']}")
        return 0
    info = cache_info(args.cache_dir)
    if args.json:
        print(dumps_json(info))
        return 0
    kinds = [e.get("kind", "basis") for e in info["entries"]]
    print(f"reduced-basis cache {info['folder']} (override: {info['override']}): {kinds.count('basis')} basis(es), "
          f"{kinds.count('preload')} preload(s), {format_bytes(info['total_bytes'])}")
    for e in info["entries"]:
        if e.get("kind", "basis") == "preload":
            print(f"  {e['key'][:12]}  {format_bytes(e['bytes']):>10}  preload of {e.get('model', '?')} under "
                  f"{e.get('normal_load_n')} N; built {e.get('built', '?')} in "
                  f"{e.get('build_seconds', float('nan')):.3g} s")
            continue
        print(f"  {e['key'][:12]}  {format_bytes(e['bytes']):>10}  {e.get('model', '?')}; "
              f"{e.get('boundary_nodes', '?')} boundary nodes, cut-off {e.get('cutoff_hz', float('nan')):.4g} Hz, "
              f"mass scaling {e.get('mass_scaling_hz', 0.0):.4g} Hz; built {e.get('built', '?')} in "
              f"{e.get('build_seconds', float('nan')):.3g} s")
    return 0
