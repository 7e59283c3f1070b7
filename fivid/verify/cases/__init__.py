"""The shipped verification cases, one small module each (discovered by :mod:`fivid.verify.registry`).

A module defines ``CASES``: a tuple of :class:`fivid.verify.case.Case`. Module names start with the part of
fivid they check (``solver_``, ``contact_``, ``fe_``, ``friction_``, ``signal_``, ``surface_``, ``identify_``),
which orders the catalogue.
"""
