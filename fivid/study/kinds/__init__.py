"""The shipped study kinds, registered in this order (the order :func:`fivid.study.kind.guess_kind` asks them
in): Hoffmann's 2-DOF model, roughness noise, convergence, weak/strong, ring regimes, and last the plain FE sweep
that any FE study falls back to. One module per kind; a new kind is one module plus a YAML (docs/studies.md)."""

from fivid.study.kind import register_study_kind, registered_kinds, study_kind
from fivid.study.kinds import convergence, hoffmann, ring, roughness, sweep, weak_strong

__all__ = ["BUILTIN_KINDS", "study_kind", "registered_kinds"]

#: the shipped kinds, in registration order
BUILTIN_KINDS = (hoffmann.KIND, roughness.KIND, convergence.KIND, weak_strong.KIND, ring.KIND, sweep.KIND)

for _kind in BUILTIN_KINDS:
    register_study_kind(_kind)
