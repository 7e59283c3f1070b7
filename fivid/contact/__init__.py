"""Contact laws and rigid contact surfaces (layer L2): one definition per law for every analysis.

:mod:`fivid.contact._kernels` holds the force, tangent and energy of each normal law, the friction curve and
the rigid-surface geometry as jitted scalar functions; the explicit solver, the static preload solve and the
modal/CEA linearisation all call them. :mod:`fivid.contact.laws` holds the parameters (and the
Greenwood-Williamson rough-surface model fitted by a power law).
"""

from fivid.contact.laws import (
    RIGID,
    GreenwoodWilliamson,
    NormalLaw,
    RigidSurface,
    composite_modulus,
    kernel_row,
    kernel_tables,
)

__all__ = ["RIGID", "GreenwoodWilliamson", "NormalLaw", "RigidSurface", "composite_modulus",
           "kernel_row", "kernel_tables"]
