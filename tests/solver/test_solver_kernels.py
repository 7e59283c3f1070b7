"""Solver kernels against obviously-correct references: scipy's assembled K, a naive numpy time loop, py_func."""

import numpy as np
import pytest

from fivid.fe import load_model, lumped_mass, stiffness_matrix
from fivid.solver.stencil import apply_stencils, block_stencils
from tests.helpers.solver_models import F32_RES, block_on_base, cantilever, stencil_bound, stencil_matrix

EPS = np.finfo(float).eps


@pytest.mark.parametrize("config", ["configs/models/triboair_coarse.yaml", cantilever(mapped=True),
                                    cantilever(sheared=True), block_on_base()],
                         ids=["rig-coarse", "mapped-block", "parallelogram-block", "block-on-base"])
def test_stencil_equals_assembled_stiffness(root, config):
    """K u by the stencil equals fivid.fe's assembled CSR K u to round-off.

    Both sum the same element entries in a different order; each entry of K u is a sum of at most
    4 elements x 8 terms = 32 products, so the difference is bounded by ~32 eps sum_j |K_ij||u_j|.
    A uniform block uses one element's stiffness for all interior nodes, accepted when every element
    agrees to 1e-12 of the largest entry (block_stencils): that adds at most 4 elements x 18 dofs x
    1e-12 max|K_e| max|u|. Mapped blocks store their coefficients in float32, difference form: + 2^-24
    sum_j |K_ij| |u_j - u_own| (:func:`tests.helpers.solver_models.stencil_bound`).
    """
    model = load_model(root / config if isinstance(config, str) else config)
    springs = bool(model.springs)
    K = stiffness_matrix(model, include_springs=False)
    st = block_stencils(model)
    u = np.random.default_rng(1).standard_normal(model.n_dofs)
    f = apply_stencils(st, u)
    ke_max = abs(K).max()  # >= max|K_e|: the assembled diagonal sums positive element diagonals
    bound = stencil_bound(K, u) + 4 * 18 * 1e-12 * ke_max * np.abs(u).max()
    assert np.all(np.abs(f - K @ u) <= bound + 1e-300)
    assert springs == bool(model.springs)


def test_mapped_block_uses_per_node_coefficients():
    st = block_stencils(load_model(cantilever(mapped=True)))
    # one mapped patch of all 17 x 4 nodes with per-node coefficients, nothing listed
    assert st.blocks.tolist() == [[st.pad, 17, 4, 17, 2, 0, 0, 0]] and st.lst_idx.size == 0 and st.c_map.shape == (32, 68)
    st = block_stencils(load_model(cantilever()))
    assert st.blocks.shape[0] == 5 and st.lst_idx.size == 4  # interior + 4 edges; corners listed
    # rectangles: the 13-term stencil in the interior; at an edge one element row is missing and the xy
    # couplings no longer cancel: full 18 terms
    assert st.blocks[:, 4].tolist() == [1, 0, 0, 0, 0]
    st = block_stencils(load_model(cantilever(sheared=True)))
    assert st.blocks.shape[0] == 5 and not st.blocks[:, 4].any()  # parallelograms: uniform, full 18 terms


def test_mapped_float32_difference_form_against_the_assembled_stiffness():
    """The mapped patches' float32 coefficients in difference form (issue 26 item 5) against the float64 assembled K.

    Each stored coefficient is K's rounded to nearest float32, so node m's force moves by at most 2^-24 sum_k
    |C_mk| |w_k - w_m| (plus float64 round-off): the bound scales with the deformation, not with the displacement.
    A field that is a large rigid translation (1e4 of the deformation, a sliding block's) plus a small random
    deformation meets it; float32 coefficients applied to w_k itself would miss it by ~2^-24 |K| |t| -- 1e4 times
    the deformation's share: the difference form is what keeps the error relative to the strain. A pure translation
    gives exactly zero force (w_k - w_m is exactly 0), a sheared trapezoidal block's as a rectangle's."""
    model = load_model(cantilever(mapped=True))
    st = block_stencils(model)
    assert st.c_map.dtype == np.float32 and st.blocks[:, 4].tolist() == [2]
    K = stiffness_matrix(model, include_springs=False)
    rng = np.random.default_rng(5)
    t = np.tile([7e-5, -3e-5], model.n_nodes)  # 70 um, 30 um: a slider's travel
    assert not np.any(apply_stencils(st, t))  # exactly zero
    w = t + 1e-9 * rng.standard_normal(model.n_dofs)
    err = np.abs(apply_stencils(st, w) - K @ w)
    bound = stencil_bound(K, w)
    assert np.all(err <= bound)
    # the bound is not loose: the float32 rounding shows, within a factor 30 of the worst case at the worst node
    assert err.max() >= bound.max() / 30
    # the test discriminates: K rounded to float32 and applied to w itself (not in difference form) misses the bound
    k32 = K.astype(np.float32).astype(float)
    assert np.abs(k32 @ w - K @ w).max() > 100 * bound.max()


def _prepare(model, n_int, n_sub, dt):
    from fivid.friction import FrictionInput, OperatingCondition
    from fivid.friction.injection import friction_table
    from fivid.solver.setup import LoadingSequence, kernel_arrays

    st = block_stencils(model)
    sched = LoadingSequence(None, 0.0, 0.0, None, 0.0)
    ka = kernel_arrays(model, st, sched, tangential_sign=1.0, normal_sign=1.0)
    fric = friction_table(model, ka.slave_pair, np.zeros(ka.slave_pair.size), FrictionInput(),
                          OperatingCondition(sliding_velocity=0.0), total_time=1.0, dt=dt, sample_rate=1.0)
    return st, ka, fric


def _run(fn, model, st, ka, fric, n_int, n_sub, dt, u0, v0, active=None):
    from fivid.solver import _kernels as K
    from fivid.solver import _loop_kernels as L
    from fivid.solver.integrate import loop_arguments, loop_state

    u = st.to_kernel(u0)
    v = st.to_kernel(v0)
    npairs = ka.master_ptr.size - 1
    rec = np.zeros((n_int, K.N_REC))
    sens = np.zeros((n_int, ka.sens_node.size, 2))
    contact = np.zeros((n_int, npairs, 5))
    fixed = loop_arguments(model, st, ka, fric, dt, 100, 1e-12)
    if active is not None:  # the predictor's dof ranges (default: the dofs with mass)
        fixed = (fixed[0], fixed[1]._replace(active=active), *fixed[2:])
    cs, state = loop_state(st, ka, u, v, model.rayleigh_beta)
    records = L.Records(rec, sens, contact, np.zeros(2, dtype=np.int64), ka.sens_node, ka.sens_dir)
    status, done = fn(0, n_int * n_sub, dt, n_sub, 2.0, *fixed, cs, state, records)
    assert status == K.OK and done == n_int
    return st.to_global(u), st.to_global(v), rec, contact


@pytest.mark.parametrize("cutoff", [None, "200 kHz"])
def test_time_loop_equals_naive_numpy_central_difference(cutoff):
    """run_steps (no contact) vs a plain numpy loop doing the same arithmetic with scipy's K and the springs,
    with classic and with band-limited Rayleigh damping (the stiffness term on the filtered velocity).

    Same operations in a different summation order: after N steps the difference stays at the level of
    float resolution amplified by the (stable, bounded) propagation, ~ N eps |u|; N = 400 gives 1e-13 |u|.
    Bound: 4 roundings per step that differ between the two (summation order of f, the two updates); the
    filter adds two more (its difference and its update), so 6 with it.
    """
    roundings = 4 if cutoff is None else 6
    cfg = cantilever(beta=2e-8, spring=2e5)
    if cutoff:
        cfg["damping"] = dict(cfg["damping"], cutoff=cutoff)
    model = load_model(cfg)
    from fivid.solver.timestep import stable_step

    dt = 0.9 * stable_step(model).critical_time_step
    n_int, n_sub = 20, 20
    st, ka, fric = _prepare(model, n_int, n_sub, dt)
    rng = np.random.default_rng(2)
    u0 = 1e-7 * rng.standard_normal(model.n_dofs)
    u0[model.fixed_dofs] = 0.0
    v0 = model.initial_velocity()
    v0[model.fixed_dofs] = 0.0
    from fivid.solver import _loop_kernels as L

    u, v, rec, _ = _run(L.run_steps, model, st, ka, fric, n_int, n_sub, dt, u0, v0)
    # naive reference
    Kfull = stiffness_matrix(model, include_springs=True)
    m = lumped_mass(model)
    c = np.zeros(model.n_dofs)
    s = model.springs[0]
    c[2 * s.node_a + s.component] = s.damping
    a, b = model.rayleigh_alpha, model.rayleigh_beta
    gain = 1.0 if cutoff is None else 1.0 - np.exp(-2 * np.pi * model.damping_cutoff * dt)
    assert gain < 1.0 or cutoff is None
    ur, vr = u0.copy(), v0.copy()
    vfr = vr.copy()
    free = model.free_dofs
    for _ in range(n_int * n_sub):
        f = Kfull @ (ur + b * vfr) - b * 0.0 + c * vr
        # springs have no beta term in fivid: remove beta K_spring v, add their dashpot
        f -= b * (Kfull - stiffness_matrix(model, include_springs=False)) @ vfr
        vr[free] = vr[free] + dt * (-f[free] / m[free] - a * vr[free])
        ur[free] += dt * vr[free]
        vfr = vfr + gain * (vr - vfr)
    scale = np.abs(ur).max()
    assert np.abs(u - ur).max() <= n_int * n_sub * EPS * scale * roundings
    assert np.abs(v - vr).max() <= n_int * n_sub * EPS * np.abs(vr).max() * roundings


@pytest.mark.parametrize("cutoff", [False, True])
def test_predictor_over_the_massive_dofs_equals_the_full_loop(cutoff):
    """The predictor integrates only the dofs with mass (``Structure.active``, :func:`massive_ranges`): on a block
    coarsening in tied levels (its tied nodes massless) the run is bit for bit the one whose predictor sweeps every
    entry -- every dof's displacement and velocity and every record -- with classic and band-limited damping."""
    from fivid.fe.transition import transition_model
    from fivid.solver import _loop_kernels as L
    from fivid.solver.integrate import massive_ranges
    from fivid.solver.timestep import stable_step
    from tests.fe.test_fe_transition import _block

    import dataclasses

    model = transition_model(_block(96, 1, length=12e-3, depth=2e-3, amplitude=5e-6), ["lower"], max_width=1e-3)
    model = dataclasses.replace(model, rayleigh_alpha=300.0, rayleigh_beta=1e-9,
                                damping_cutoff=2e5 if cutoff else np.inf)
    dt = 0.9 * stable_step(model).critical_time_step
    n_int, n_sub = 5, 20
    st, ka, fric = _prepare(model, n_int, n_sub, dt)
    ranges = massive_ranges(ka.mass)
    assert 1 < ranges.shape[0] and (ranges[:, 1] - ranges[:, 0]).sum() < 0.9 * ka.mass.size  # tied rows skipped
    rng = np.random.default_rng(4)
    u0 = 1e-7 * rng.standard_normal(model.n_dofs)
    v0 = 1e-2 * rng.standard_normal(model.n_dofs)
    for x in (u0, v0):
        x[model.fixed_dofs] = 0.0
        x[model.tied_dofs] = 0.0  # a tied node has no state of its own
    out = _run(L.run_steps, model, st, ka, fric, n_int, n_sub, dt, u0, v0)
    full = _run(L.run_steps, model, st, ka, fric, n_int, n_sub, dt, u0, v0,
                active=np.array([[0, ka.mass.size]], dtype=np.int64))
    for a, b in zip(out, full):
        np.testing.assert_array_equal(a, b)
    assert np.abs(out[0]).max() > 1e-7  # it moved


def test_kernel_equals_py_func_with_contact_and_friction():
    """The jitted time loop and its pure-Python version agree to round-off on a contact run with slip."""
    from fivid.solver import _loop_kernels as L
    from fivid.solver.timestep import stable_step

    model = load_model(block_on_base(v0=0.5))
    dt = 0.9 * stable_step(model).critical_time_step
    n_int, n_sub = 3, 10
    st, ka, fric = _prepare(model, n_int, n_sub, dt)
    u0 = np.zeros(model.n_dofs)
    # start pressed: block pushed 5 nm into the base (the contact must act from step 1)
    block = model.block("block")
    u0[2 * block.node_numbers().ravel() + 1] = -5e-9
    v0 = model.initial_velocity()
    v0[model.fixed_dofs] = 0.0
    out_jit = _run(L.run_steps, model, st, ka, fric, n_int, n_sub, dt, u0, v0)
    out_py = _run(getattr(L.run_steps, "py_func", L.run_steps), model, st, ka, fric, n_int, n_sub, dt, u0, v0)
    for a, b in zip(out_jit, out_py):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12 * np.abs(b).max())
    contact = out_jit[3]
    assert contact[-1, 0, 0] > 0.0  # pressed
    assert contact[-1, 0, 3] > 0.0  # some slave nodes slip (block moving at 0.5 m/s)


def test_time_loop_with_pressure_equals_naive_numpy_central_difference():
    """run_steps with a ramped pressure load vs a plain numpy loop: f = K u - r(t_n) F at the step start, the same
    smooth ramp r(s) = s - sin(2 pi s)/(2 pi), on a trapezoidal (mapped: per-node stencil) cantilever, the numpy
    loop with the stencil's own matrix. Same bound as the load-free comparison (~ N eps |u|); the load work recorded
    by the kernel equals sum_n dt F_n . v_mid."""
    from fivid.fe import external_load_vector
    from fivid.solver import _kernels as K
    from fivid.solver import _loop_kernels as L
    from fivid.solver.timestep import stable_step

    cfg = cantilever(mapped=True, v0=0.0)
    cfg["loads"] = [{"name": "p", "body": "beam", "edge": "top", "pressure": "5 MPa", "ramp_time": "0.02 ms"}]
    model = load_model(cfg)
    dt = 0.9 * stable_step(model).critical_time_step
    n_int, n_sub = 20, 20
    st, ka, fric = _prepare(model, n_int, n_sub, dt)
    zero = np.zeros(model.n_dofs)
    u, v, rec, _ = _run(L.run_steps, model, st, ka, fric, n_int, n_sub, dt, zero, zero)
    # the stencil's own matrix (float32 mapped coefficients: not the assembled K to round-off, see
    # test_mapped_float32_difference_form_against_the_assembled_stiffness); the loop's arithmetic is what is tested
    Kfull = stencil_matrix(st, model.n_dofs)
    m = lumped_mass(model)
    F = external_load_vector(model)
    tr = model.loads[0].ramp_time
    free = model.free_dofs
    ur, vr = zero.copy(), zero.copy()
    wload = 0.0
    for step in range(n_int * n_sub):
        s = min(step * dt / tr, 1.0)
        fl = (s - np.sin(2 * np.pi * s) / (2 * np.pi)) * F
        f = Kfull @ ur - fl
        vo = vr.copy()
        vr[free] = vr[free] - dt * f[free] / m[free]
        ur[free] += dt * vr[free]
        wload += dt * fl @ (0.5 * (vo + vr))
    scale = np.abs(ur).max()
    assert scale > 0
    assert np.abs(u - ur).max() <= n_int * n_sub * EPS * scale * 4
    np.testing.assert_allclose(rec[-1, K.R_WLOAD], wload, rtol=n_int * n_sub * EPS * 4)


def test_rotated_ring_stencils_give_the_per_node_run(root, monkeypatch):
    """The ring of ring_pressure.yaml (360 x 20, under pressure) run 1 ms with one stencil per radial layer in the
    column frames (the default) and with per-node stencils: the same run to the stencils' agreement.

    The rotated stencils differ from the per-node ones by at most ``eps_K = 36 SAME_STENCIL_RTOL`` relative to the
    largest coefficient (test_fe_geometry), the per-node ones (float32, difference form) from K by ``2^-24`` of each
    of their 32 coefficients and as much again on the node's own coupling (``64 2^-24``); a relative stiffness
    change ``eps_K`` moves every mode's frequency by
    at most ``eps_K / 2`` relative, so a response over ``t`` by at most ~``eps_K omega_max t`` relative
    (``omega_max ~ 2 / dt``: the fastest mode's phase), 1e-6 here; a wrong rotation or row would be O(1) off."""
    import functools

    from fivid.solver import FrictionInput, OperatingCondition, OutputOptions, RunSchedule, simulate
    from fivid.solver import stencil as S

    model = load_model(root / "configs/models/ring_pressure.yaml")
    assert block_stencils(model).blocks[:, 4].tolist() == [S.PATCH_ROTATED]
    args = dict(schedule=RunSchedule(duration=1e-3, sample_rate=51200.0), output=OutputOptions(progress=False))
    rotated = simulate(model, OperatingCondition(), FrictionInput(), **args)
    monkeypatch.setattr(S, "block_stencils", functools.partial(S.block_stencils, rotated=False))
    per_node = simulate(model, OperatingCondition(), FrictionInput(), **args)
    t = float(per_node.time[-1])
    eps = (36 * S.SAME_STENCIL_RTOL + 64 * F32_RES) * (2.0 / per_node.attrs["time_step"]) * t
    for name in ("acceleration", "sensor_velocity", "strain_energy", "kinetic_energy"):
        a, b = rotated[name].values, per_node[name].values
        assert np.abs(a - b).max() <= eps * np.abs(b).max(), name
