"""Friction dampers (seed 004): Jenkins contact on a beam, FRFs by harmonic balance, identification."""
