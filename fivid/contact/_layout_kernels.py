"""The parameter record of a contact pair for the kernels: one row of :data:`NPAR` floats (layer L0).

Every column has a name here and nowhere else: the row is written by :func:`fivid.contact.kernel_row` (the normal
law, the friction curve :meth:`fivid.friction.FrictionCurve.columns` and the rigid master
:meth:`fivid.contact.RigidSurface.columns`, each at its columns) and read by the kernels
(:mod:`fivid.contact._kernels`, :mod:`fivid.solver._contact_kernels`) through these module-level integer
constants, which numba folds in as compile-time constants. No other module indexes a row by number. (Data only;
the ``_kernels`` suffix puts it in layer L0, where kernels may import it.)

==================== ====================================================================================
column               meaning
==================== ====================================================================================
``LAW``              normal law: :data:`LAW_RIGID` (Lagrange multipliers, no penetration), :data:`LAW_LINEAR`
                     ``p = c d``, :data:`LAW_POWER` ``p = c d**n``, :data:`LAW_TABLE` (tabulated ``p(d)``)
``LAW_COEFFICIENT``  ``c`` [Pa m-1] (linear), [Pa m-n] (power) or the table's penetration step [m]
``LAW_EXPONENT``     ``n`` [-] (power)
``MU_STATIC_EXCESS`` ``mu_s - mu_k``: static excess of the friction coefficient [-]
``STRIBECK_VELOCITY`` ``v_s`` [m s-1] (0: no Stribeck curve, a step from ``mu_s`` to ``mu_k``)
``VISCOUS``          viscous friction coefficient ``c_v`` [s m-1]:
                     ``mu(v) = mu_k + (mu_s - mu_k) exp(-|v|/v_s) + c_v |v|``
``MASTER``           :data:`MASTER_EDGE` a deformable body's edge (node-to-segment), :data:`MASTER_LINE` rigid
                     line, :data:`MASTER_CIRCLE` rigid circle
``SURFACE_X, _Y``    line: a point on it [m]; circle: its centre [m]
``SURFACE_A, _B``    line: unit normal pointing to the slave side; circle: radius [m] and side (+1: slave
                     outside, -1 inside)
``SURFACE_SX, _SY``  line: surface velocity [m s-1] (along the line); circle: angular velocity [rad s-1]
                     (counter-clockwise positive) and unused
``SURFACE_START``,   surface motion start time and ramp time [s] (smooth ramp ``r(s) = s - sin(2 pi s)/(2 pi)``)
``SURFACE_RAMP``
``EXPANSION``        circle: radial displacement ``delta`` [m] its radius grows by (the preload; 0 for a line)
``EXPANSION_START``, start and ramp time of the expansion [s] (the same smooth ramp: radius
``EXPANSION_RAMP``   ``a + delta r(t)``, :func:`fivid.contact._kernels.circle_radius`)
==================== ====================================================================================

The friction curve's three columns are contiguous (:data:`FRICTION_FIRST` .. :data:`FRICTION_FIRST` + 2), as
are the rigid surface's twelve (:data:`MASTER` .. :data:`EXPANSION_RAMP`).

The solver's three contact scratch records are named here too. ``geo`` (one row of :data:`N_GEO` per slave, written by
the geometry pass of :func:`fivid.solver._contact_kernels.contact_solve` each step):

======================== ================================================================================
column                   meaning
======================== ================================================================================
``GEO_N0``, ``GEO_N1``   shape values of the master segment's two nodes at the slave's projection [-]
``GEO_NX``, ``GEO_NY``   unit outward normal of the master [-]
``GEO_TX``, ``GEO_TY``   unit tangent of the master [-]
``GEO_INSIDE``           1: the slave faces its master (projects onto it), else 0
``GEO_PENETRATION``      penetration [m] of a compliant law after the solve (0 for the rigid law)
``GEO_SURFACE_VELOCITY`` a rigid master's surface velocity along the tangent [m s-1]
``GEO_GAP``              the gap [m] in the predicted configuration (deformable master)
``GEO_IDLE``             1: an open slave left out of the Gauss-Seidel sweeps (gap beyond the candidate margin),
                         else 0
``GEO_SLEEP``            > 0: a sleeping slave's remaining displacement budget [m] (not located while it lasts;
                         see :func:`fivid.solver._contact_kernels.contact_solve`), else 0
======================== ================================================================================

``rec_contact`` (one row of :data:`N_REC_CONTACT` per pair and output interval): ``REC_NORMAL``, ``REC_TANGENTIAL``
the summed multipliers [N] (interval averages once finished), ``REC_STICK``, ``REC_SLIP``, ``REC_OPEN`` the slaves
in each state (fractions once finished); ``REC_STICK - 1 + cstate`` is the column of a closed slave's state
``cstate`` (1 stick, 2 slip). ``vold_c`` (one row of :data:`N_CNODE` per contact node): ``CNODE_V_STEP`` and
``CNODE_V_STEP + 1`` its x and y velocity [m s-1] before the step, ``CNODE_V_PREDICTED`` (+ 1) before the contact
correction, ``CNODE_MOVED`` the bound ``sum |dx| + |dy|`` [m] of the displacements the step's contact corrections
gave it (zeroed after each solve).
"""

__all__ = ["NPAR", "LAW", "LAW_COEFFICIENT", "LAW_EXPONENT", "MU_STATIC_EXCESS", "STRIBECK_VELOCITY", "VISCOUS",
           "FRICTION_FIRST", "MASTER", "SURFACE_X", "SURFACE_Y", "SURFACE_A", "SURFACE_B", "SURFACE_SX",
           "SURFACE_SY", "SURFACE_START", "SURFACE_RAMP", "EXPANSION", "EXPANSION_START", "EXPANSION_RAMP",
           "LAW_RIGID", "LAW_LINEAR", "LAW_POWER", "LAW_TABLE", "MASTER_EDGE", "MASTER_LINE", "MASTER_CIRCLE",
           "GEO_N0", "GEO_N1", "GEO_NX", "GEO_NY", "GEO_TX", "GEO_TY", "GEO_INSIDE", "GEO_PENETRATION", "GEO_SURFACE_VELOCITY", "GEO_GAP", "GEO_IDLE",
           "GEO_SLEEP",
           "N_GEO", "REC_NORMAL", "REC_TANGENTIAL", "REC_STICK", "REC_SLIP", "REC_OPEN", "N_REC_CONTACT",
           "CNODE_V_STEP", "CNODE_V_PREDICTED", "CNODE_MOVED", "N_CNODE"]

# normal law
LAW = 0
LAW_COEFFICIENT = 1
LAW_EXPONENT = 2
# friction curve over the kinetic coefficient (fivid.friction.FrictionCurve.columns, in this order)
MU_STATIC_EXCESS = 3
STRIBECK_VELOCITY = 4
VISCOUS = 5
FRICTION_FIRST = MU_STATIC_EXCESS
# master (fivid.contact.RigidSurface.columns, in this order)
MASTER = 6
SURFACE_X = 7
SURFACE_Y = 8
SURFACE_A = 9
SURFACE_B = 10
SURFACE_SX = 11
SURFACE_SY = 12
SURFACE_START = 13
SURFACE_RAMP = 14
EXPANSION = 15
EXPANSION_START = 16
EXPANSION_RAMP = 17
#: columns of a row
NPAR = 18

# codes of the LAW column
LAW_RIGID = 0
LAW_LINEAR = 1
LAW_POWER = 2
LAW_TABLE = 3
# codes of the MASTER column
MASTER_EDGE = 0
MASTER_LINE = 1
MASTER_CIRCLE = 2

# the solver's per-slave geometry record (geo)
GEO_N0 = 0
GEO_N1 = 1
GEO_NX = 2
GEO_NY = 3
GEO_TX = 4
GEO_TY = 5
GEO_INSIDE = 6
GEO_PENETRATION = 7
GEO_SURFACE_VELOCITY = 8
GEO_GAP = 9
GEO_IDLE = 10
GEO_SLEEP = 11
#: columns of a geo row
N_GEO = 12

# the solver's per-pair contact record (rec_contact)
REC_NORMAL = 0
REC_TANGENTIAL = 1
REC_STICK = 2
REC_SLIP = 3
REC_OPEN = 4
#: columns of a rec_contact row
N_REC_CONTACT = 5

# the solver's per-contact-node scratch (vold_c)
CNODE_V_STEP = 0
CNODE_V_PREDICTED = 2
CNODE_MOVED = 4
#: columns of a vold_c row
N_CNODE = 5
