"""Helpers shared by the tests (imported as ``from _helpers import ...``).

Eigenvalues come back from LAPACK in an order that is not stable across versions: sorting them
(``np.sort_complex``) is fragile too, because the real parts of a conjugate pair can differ by
rounding (1e-14) and the pair then swaps. Compare them as sets instead.
"""

from __future__ import annotations

from collections import defaultdict

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import linear_sum_assignment


def assert_same_eigenvalues(
    actual: ArrayLike, desired: ArrayLike, *, rtol: float = 1e-7, atol: float = 0.0
) -> None:
    """Assert two multisets of (complex) eigenvalues are equal within tolerance.

    The two are paired by an optimal matching (least total distance ``|a_i - b_j|``,
    ``scipy.optimize.linear_sum_assignment``), so the result does not depend on their order;
    then each pair is compared as ``np.testing.assert_allclose`` does.
    """
    a = np.asarray(actual, dtype=complex).ravel()
    b = np.asarray(desired, dtype=complex).ravel()
    assert a.shape == b.shape, f"{a.size} eigenvalues vs {b.size}: {a} vs {b}"
    rows, cols = linear_sum_assignment(np.abs(a[:, None] - b[None, :]))
    np.testing.assert_allclose(
        a[rows], b[cols], rtol=rtol, atol=atol, err_msg=f"eigenvalues {a} vs {b}"
    )


def assert_same_characteristic_polynomial(
    actual: ArrayLike, desired: ArrayLike, *, rtol: float = 1e-6, atol: float = 1e-8
) -> None:
    """Assert two sets of eigenvalues have the same characteristic polynomial (``np.poly``).

    Order-free like :func:`assert_same_eigenvalues`, and well conditioned where repeated or
    clustered eigenvalues are not (a triple root moves by ~eps^(1/3) under rounding).
    """
    a = np.asarray(actual, dtype=complex).ravel()
    b = np.asarray(desired, dtype=complex).ravel()
    assert a.shape == b.shape, f"{a.size} eigenvalues vs {b.size}: {a} vs {b}"
    np.testing.assert_allclose(
        np.poly(a), np.poly(b), rtol=rtol, atol=atol, err_msg=f"eigenvalues {a} vs {b}"
    )


def _blue_lady_kwargs() -> tuple[dict, dict]:
    from shipgym.controllers.actuation import planar_capacity
    from shipgym.dynamics.vessel import load_vessel

    v = load_vessel("blue-lady")
    design = {"M": v.design.M, "D_L": v.design.D_L}
    return design, {**design, "integral_limit": planar_capacity(v)}


#: The Blue Lady's design model as keyword arguments (``M``, ``D_L``) and, with its force
#: capacity as ``integral_limit``, those of the PID and LQ controllers: no vessel is a default
#: below the registry, so the tests name the vessel they use.
BLUE_LADY_DESIGN, BLUE_LADY_CONTROL = _blue_lady_kwargs()


def read_rrd(path):
    """Per entity: static component values and temporal rows (step, sim_time, components)."""
    from rerun.chunk import RrdReader

    static = defaultdict(dict)
    rows = defaultdict(lambda: defaultdict(list))
    for ch in RrdReader(path).stream():
        rb = ch.to_record_batch()
        ent = ch.entity_path.lstrip("/")
        for i, name in enumerate(rb.schema.names):
            if name.startswith("rerun.controls"):
                continue
            col = rb.column(i)
            if ch.is_static:
                static[ent][name] = col.to_pylist()[-1]
            elif name == "sim_time":
                rows[ent][name].extend(col.cast("int64").to_pylist())
            else:
                rows[ent][name].extend(col.to_pylist())
    return static, rows


def compiled_forces(acts, st, u, v, p, r):  # type: ignore[no-untyped-def]
    """``(X, Y, K, N, forces, stalled)`` of an actuator set by its compiled laws (the physics
    step's, :func:`shipgym.dynamics.actuators.tau_of_table`) at the states ``st`` and the
    velocity through the water ``(u, v, p, r)``."""
    import numpy as np

    from shipgym.dynamics.actuators import tau_of_table

    table, laws, kinds = acts.law_table()
    forces, flags = np.zeros(len(kinds)), np.zeros(len(kinds))
    st = np.ascontiguousarray(st, dtype=np.float64)
    X, Y, K, N = tau_of_table(table, laws, kinds, st, u, v, p, r, forces, flags)
    return X, Y, K, N, forces, flags > 0


def accel_of(plant):  # type: ignore[no-untyped-def]
    """The hull family's compiled acceleration of ``plant`` (its ``accel_kernel`` with its
    constants) as a plain function: ``f(u, v, r, X, Y, N, u_c=0, v_c=0) -> (u_dot, v_dot,
    r_dot)`` for 3 DOF, ``f(u, v, p, r, phi, X, Y, K, N, u_c=0, v_c=0) -> (u_dot, v_dot,
    p_dot, r_dot)`` for 4 DOF."""
    fn, k = type(plant).accel_kernel, plant.kernel_constants()
    if getattr(plant, "dofs", 3) == 4:

        def accel4(u, v, p, r, phi, X, Y, K, N, u_c=0.0, v_c=0.0):  # type: ignore[no-untyped-def]
            args = (u, v, p, r, phi, X, Y, K, N, u_c, v_c)
            return fn(k, *(float(a) for a in args))

        return accel4

    def accel3(u, v, r, X, Y, N, u_c=0.0, v_c=0.0):  # type: ignore[no-untyped-def]
        ud, vd, _pd, rd = fn(k, float(u), float(v), 0.0, float(r), 0.0, float(X), float(Y),
                             0.0, float(N), float(u_c), float(v_c))  # fmt: skip
        return ud, vd, rd

    return accel3


def step_singles(singles, actions, pending):  # type: ignore[no-untyped-def]
    """The single envs' side of one step of a vector env in next-step autoreset mode: env
    ``i`` reset where ``pending[i]`` (its action ignored, as the vector env ignores it), else
    stepped with ``actions[i]``. Returns one ``(obs, info, stepped)`` per env, ``stepped`` the
    ``(reward, terminated, truncated)`` of a step, ``None`` after a reset."""
    out = []
    for s, a, p in zip(singles, actions, pending, strict=True):
        if p:
            o, info = s.reset()
            out.append((o, info, None))
        else:
            o, r, te, tr, info = s.step(a)
            out.append((o, info, (r, te, tr)))
    return out


def one_line_error(capsys, rc, *needles):  # type: ignore[no-untyped-def]
    """The CLI's error output read from ``capsys``: exit status 2 and one line
    ``shipgym: error: ...`` holding each of ``needles``; returns that line."""
    err = capsys.readouterr().err
    assert rc == 2, err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, err
    assert lines[0].startswith("shipgym: error: "), err
    for n in needles:
        assert n in lines[0], (n, lines[0])
    return lines[0]
