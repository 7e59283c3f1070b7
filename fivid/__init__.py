"""fivid — friction-induced vibration identification.

From friction test-rig measurements (acceleration and friction-force signals) to an identified
friction-perturbation law, a finite-element contact simulation and PSD scores of simulated against
measured vibration.

``import fivid`` is light: it imports no numba, dask or matplotlib. The subpackages are imported
where they are used::

    from fivid.io import read_rig_csv
    from fivid.signal import welch_psd
"""

__version__ = "0.1.0"

__all__ = ["__version__"]
