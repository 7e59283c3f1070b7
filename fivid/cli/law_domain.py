"""The identified-domain check of a friction law at a condition, for every command that evaluates a law.

``fivid law eval`` and ``fivid simulate --law`` (one run or ``--samples``) both call
:func:`check_law_condition`: the amplitude is predicted with :func:`fivid.friction.predict_amplitude`
(which owns the check and its wording, :meth:`fivid.friction.ConditionDomain.outside`); outside the
domain each warning is printed on stderr as ``fivid <command>: warning: ...``, naming the variable and
the identified range, and with ``strict`` the condition is refused (a :class:`~fivid.errors.FividError`:
exit status 2).
"""

from __future__ import annotations

import sys

from fivid.friction import ExtrapolationWarning, domain_from_dataset, load_law, predict_amplitude

__all__ = ["open_law_file", "check_law_condition"]


def open_law_file(path):
    """``(dataset, law, domain)`` of a law file: the law as :func:`fivid.friction.load_law` reads it (its
    source records the file's sha256), the domain from :func:`fivid.friction.domain_from_dataset` (None for
    a file that records none)."""
    from pathlib import Path

    from fivid.io.netcdf import read_run  # lazy: pulls pydantic

    law = load_law(path)
    ds = read_run(Path(path), validate=False)
    return ds, law, domain_from_dataset(ds)


def check_law_condition(law, domain, velocity, roughness, normal_load=None, *, strict: bool = False,
                        confidence: float = 0.95, command: str = "law"):
    """The law's amplitude prediction at a condition, the domain checked.

    Parameters
    ----------
    law : PerturbedCoulombLaw
    domain : ConditionDomain or None
        The law's identified domain (None: not checkable, which is said on stderr).
    velocity, roughness, normal_load : float or None
        Sliding velocity [m s-1], roughness Ra [m], normal load [N]; None where not known (not checked).
    strict : bool
        Refuse a condition outside the domain (FividError, exit 2) instead of warning.
    confidence : float
        Level of the prediction interval.
    command : str
        Name of the command in the warning lines (``fivid <command>: warning: ...``).

    Returns
    -------
    AmplitudePrediction
        One condition; ``inside`` and ``messages`` say whether and why it is outside the domain.
    """
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ExtrapolationWarning)
        pred = predict_amplitude(law.amplitude_model, velocity, roughness, normal_load, domain=domain,
                                 confidence=confidence, strict=strict)
    for w in caught:
        if issubclass(w.category, ExtrapolationWarning):
            print(f"fivid {command}: warning: {w.message}", file=sys.stderr)
        else:  # not ours: hand it on as it came
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    if domain is None:
        print(f"fivid {command}: warning: the law file records no domain: extrapolation cannot be checked",
              file=sys.stderr)
    return pred
