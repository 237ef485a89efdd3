r"""The 3-DOF physics step compiled with Numba, ``mj_step`` called from the compiled loop.

:meth:`VesselPhysics.step <shipgym.envs.physics.VesselPhysics.step>` spends most of a physics
step in CPython: the force preparation (thrust, wind, current, the hull's acceleration, the
``qfrc_applied`` that makes MuJoCo produce it) costs about twice MuJoCo's own step. Where Numba
is installed this module runs the same loop as machine code: each step evaluates the forces
and calls MuJoCo's C ``mj_step`` on the physics' own ``mjModel``/``mjData`` (by its address in
the library the ``mujoco`` package loaded), so a physics step costs about one bare
``mujoco.mj_step`` from Python.

The compiled functions are the plain-float kernels of the Python path written once more for
Numba, with the same operations in the same order, so they give the same floats:
:func:`accel3` is :meth:`PlantModel.accel <shipgym.dynamics.model.PlantModel.accel>`,
:func:`wind_load` is :meth:`WindLoad.kernel <shipgym.disturbances.wind.WindLoad.kernel>`,
:func:`thrust3` and :func:`propeller_flow` sum the rows of
:meth:`ActuatorSet.thrust_tables3 <shipgym.dynamics.actuators.ActuatorSet.thrust_tables3>`
and :meth:`~shipgym.dynamics.actuators.ActuatorSet.propeller_flow_table`, and the loop is the
``prepare3`` closure of :mod:`shipgym.envs.physics`. ``tests/test_native.py`` checks each
against its Python form bit for bit, and whole trajectories of every vessel it covers.

Covered: 3-DOF hulls with a :class:`~shipgym.dynamics.model.PlantModel`, MuJoCo-applied
propellers and azimuths, flow-dependent propellers (advance-speed and tunnel losses), servos,
rate-limited lags, wind (gusts on their sample grid), current (constant or Gauss-Markov on
its grid) and the second-order wave drift (on its grid). Anything else (4-DOF hulls, MMG
hulls and units, rudders) steps in Python. ``SHIPGYM_NATIVE=0`` turns the compiled step off
(:func:`status` says why it is off).

The compiled code is cached on disk by Numba (``cache=True``), so only the first process on a
machine compiles it (a few seconds).
"""

from __future__ import annotations

import contextlib
import ctypes
import math
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from shipgym.disturbances._grid import CHUNK
from shipgym.envs._mujoco import mujoco

__all__ = [
    "available",
    "disabled",
    "status",
    "OK",
    "NEED_WIND",
    "NEED_CURRENT",
    "DIVERGED",
    "run3",
    "run_batched3",
]

#: return codes of :func:`run3`: all steps taken (or a contact), the next wind, current or
#: wave-drift chunk is needed (the caller extends the process and calls again), the state
#: diverged
OK, NEED_WIND, NEED_CURRENT, DIVERGED, NEED_DRIFT = 0, 1, 2, 3, 4

_why_off: str | None = None
_mj_step: Any = None
try:
    if os.environ.get("SHIPGYM_NATIVE", "1").strip() == "0":
        raise ImportError("SHIPGYM_NATIVE=0")
    import numba
    from llvmlite import ir
    from numba import njit, types
    from numba.extending import intrinsic
except ImportError as exc:  # numba absent or turned off: the Python step
    _why_off = f"the compiled physics step is off ({exc})"

    def njit(*args: Any, **kwargs: Any) -> Any:  # noqa: D103 - the decorator's stand-in
        return (lambda f: f) if not args or not callable(args[0]) else args[0]


def _load_mj_step() -> Any:
    """MuJoCo's C ``mj_step`` from the shared library the ``mujoco`` package loaded."""
    here = Path(mujoco.__file__).parent
    libs = sorted(here.glob("libmujoco.so*")) + sorted(here.glob("libmujoco*.dylib"))
    if not libs:
        raise OSError(f"no libmujoco shared library next to {here}")
    lib = ctypes.CDLL(str(libs[0]))
    f = lib.mj_step
    f.argtypes = [ctypes.c_void_p, ctypes.c_void_p]
    f.restype = None
    return f


if _why_off is None:
    try:
        _mj_step = _load_mj_step()
    except (OSError, AttributeError) as exc:
        _why_off = f"the compiled physics step is off (MuJoCo's library: {exc})"


_off_here = 0  # disabled() nesting depth


def available() -> bool:
    """Whether the compiled physics step is used (Numba present, not turned off)."""
    return _why_off is None and _off_here == 0


@contextlib.contextmanager
def disabled() -> Iterator[None]:
    """Physics built inside the block step in Python (for comparing the two forms)."""
    global _off_here
    _off_here += 1
    try:
        yield
    finally:
        _off_here -= 1


def status() -> str:
    """One line: on, with the Numba version, or why it is off."""
    if _why_off is None:
        return f"compiled physics step on (numba {numba.__version__})"
    return _why_off


_NCON_OFFSET: int | None = None


def ncon_view(model: Any, data: Any) -> np.ndarray:
    """A one-element int32 array on ``data.ncon`` (MuJoCo's contact count), for the compiled
    loop's contact stop. The field's offset in ``mjData`` is found once, by writing two
    values through the bindings and finding the one place both appear."""
    global _NCON_OFFSET
    if _NCON_OFFSET is None:
        d = mujoco.MjData(model)  # a probe, not the caller's data
        hits = []
        for value in (0x5A17C0DE, 0x0BADF00D):
            d.ncon = value
            raw = np.frombuffer(ctypes.string_at(d._address, 1 << 18), dtype=np.int32)
            hits.append(set(np.nonzero(raw == value)[0].tolist()))
        d.ncon = 0
        both = hits[0] & hits[1]
        if len(both) != 1:
            raise RuntimeError("cannot locate mjData.ncon for the compiled physics step")
        _NCON_OFFSET = 4 * both.pop()
    view = (ctypes.c_int32 * 1).from_address(data._address + _NCON_OFFSET)
    arr = np.ctypeslib.as_array(view)
    if int(arr[0]) != int(data.ncon):
        raise RuntimeError("mjData.ncon is not where the compiled physics step looked")
    return arr


def mj_step_address() -> int:
    """The address of MuJoCo's C ``mj_step`` (an int, passed to :func:`run3`: an address
    argument keeps the compiled code cacheable across processes, where a ctypes function
    bound into it would not be)."""
    return int(ctypes.cast(_mj_step, ctypes.c_void_p).value or 0)


if _why_off is None:

    @intrinsic
    def _call(typingctx, fn, m, d):  # type: ignore[no-untyped-def]
        """``fn(m, d)``: call the C function at address ``fn`` with two pointers."""
        sig = types.void(types.intp, types.intp, types.intp)

        def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
            f, mp, dp = args
            ptr = ir.IntType(8).as_pointer()
            fnty = ir.FunctionType(ir.VoidType(), [ptr, ptr])
            target = builder.inttoptr(f, fnty.as_pointer())
            builder.call(target, [builder.inttoptr(mp, ptr), builder.inttoptr(dp, ptr)])
            return context.get_dummy_value()

        return sig, codegen

else:

    def _call(fn: int, m: int, d: int) -> None:  # never called: the Python step runs
        raise RuntimeError(_why_off)


def table(rows: Any, width: int) -> np.ndarray:
    """Rows of constants as a ``(len(rows), width)`` float array (``(0, width)`` for none)."""
    return np.array(rows, dtype=np.float64).reshape(len(rows), width)


def actuator_tables(acts: Any) -> tuple[np.ndarray, ...]:
    """The rows :func:`thrust3` and :func:`propeller_flow` sum, as arrays: ``(varying,
    lateral, static, azimuths, flow propellers)`` of an ``ActuatorSet``
    (:meth:`~shipgym.dynamics.actuators.ActuatorSet.thrust_tables3`,
    :meth:`~shipgym.dynamics.actuators.ActuatorSet.propeller_flow_table`)."""
    rows = acts.thrust_tables3()
    widths = (7, 4, 5, 4)
    out = tuple(table(r, w) for r, w in zip(rows, widths, strict=True))
    return (*out, table(acts.propeller_flow_table() or (), 11))


def parameters(plant: Any, wind_load: Any) -> np.ndarray:
    """A zeroed parameter vector of :func:`run3` / :func:`run_batched3` holding the plant's
    constants (``kernel_constants``) and the wind load's (``WindLoad.kernel_constants``)."""
    from shipgym.dynamics.model import kernel_constants

    fp = np.zeros(_FP_SIZE)
    fp[_FP_PLANT:_FP_WIND] = kernel_constants(plant)
    fp[_FP_WIND:_FP] = wind_load.kernel_constants()
    return fp


# ---- the kernels ---------------------------------------------------------------------------
@njit(cache=True, inline="always")
def accel3(k, u, v, r, X, Y, N, u_c, v_c):  # type: ignore[no-untyped-def]
    """:meth:`PlantModel.accel` with its constants ``k`` (:func:`plant_constants`)."""
    a11, a22, a32 = k[0], k[1], k[2]
    d11, d12, d13, d21, d22, d23, d31, d32, d33 = (
        k[3],
        k[4],
        k[5],
        k[6],
        k[7],
        k[8],
        k[9],
        k[10],
        k[11],
    )
    q1, q2, q3 = k[12], k[13], k[14]
    i11, i12, i13, i21, i22, i23, i31, i32, i33 = (
        k[15], k[16], k[17], k[18], k[19], k[20], k[21], k[22], k[23]
    )  # fmt: skip
    m, mxg, xg, a22c, a23c, a11c = k[24], k[25], k[26], k[27], k[28], k[29]
    ur = u - u_c
    vr = v - v_c
    fx = X - (d11 * ur + d12 * vr + d13 * r + q1 * abs(ur) * ur)
    fy = Y - (d21 * ur + d22 * vr + d23 * r + q2 * abs(vr) * vr)
    fn = N - (d31 * ur + d32 * vr + d33 * r + q3 * abs(r) * r)
    w = a22c * vr + a23c * r
    a11u = a11c * ur
    fx += m * (xg * r + v) * r + w * r
    fy -= m * u * r + a11u * r
    fn -= mxg * r * u + w * ur - a11u * vr
    ay = -r * u_c
    fx += a11 * (r * v_c)
    fy += a22 * ay
    fn += a32 * ay
    return (
        i11 * fx + i12 * fy + i13 * fn,
        i21 * fx + i22 * fy + i23 * fn,
        i31 * fx + i32 * fy + i33 * fn,
    )


@njit(cache=True, inline="always")
def wind_load(k, psi, u, v, V_w, beta_w):  # type: ignore[no-untyped-def]
    """:meth:`WindLoad.kernel`'s load with its constants ``k`` (:func:`wind_constants`)."""
    cd_t, cd_pi, cd_0, half_delta, ratio, arm0, kx, ky, kn = (
        k[0], k[1], k[2], k[3], k[4], k[5], k[6], k[7], k[8]
    )  # fmt: skip
    pi, half_pi, slope = k[9], k[10], k[11]
    ang = beta_w - pi - psi
    u_rw = u - V_w * math.cos(ang)
    v_rw = v - V_w * math.sin(ang)
    v2 = u_rw * u_rw + v_rw * v_rw
    vr = math.sqrt(v2)
    g = math.atan2(abs(v_rw), u_rw)
    inv = 1.0 / vr if vr != 0.0 else 1.0
    c = u_rw * inv
    s = -v_rw * inv
    cd_laf = cd_0 if g <= half_pi else cd_pi
    cs = c * s
    den = 1.0 - half_delta * (1.0 - cd_laf * ratio) * (4.0 * cs * cs)
    cy = cd_t * s / den
    return (
        kx * v2 * (-cd_laf * c / den),
        ky * v2 * cy,
        kn * v2 * ((arm0 - slope * (g - half_pi)) * cy),
    )


@njit(cache=True, inline="always")
def thrust3(st, varying, lateral, static, azim, gain, gear, write):  # type: ignore[no-untyped-def]
    """The 3-DOF ``tau_of`` of :meth:`ActuatorSet.kernel` over the rows of
    :meth:`ActuatorSet.thrust_tables3` (as arrays); with ``write`` it refreshes MuJoCo's
    state-dependent gains and azimuth directions as the Python kernel does."""
    X = 0.0
    Y = 0.0
    N = 0.0
    for row in range(varying.shape[0]):
        j = int(varying[row, 0])
        kp, kn, quad, c, s, mn = (
            varying[row, 1], varying[row, 2], varying[row, 3], varying[row, 4],
            varying[row, 5], varying[row, 6],
        )  # fmt: skip
        a = st[j]
        g = kp if a >= 0.0 else kn
        if quad != 0.0:
            g *= abs(a)
        f = g * a
        if write:
            gain[j, 0] = g
        X += c * f
        Y += s * f
        N += mn * f
    for row in range(lateral.shape[0]):
        j = int(lateral[row, 0])
        f = lateral[row, 1] * st[j]
        Y += lateral[row, 2] * f
        N += lateral[row, 3] * f
    for row in range(static.shape[0]):
        j = int(static[row, 0])
        f = static[row, 1] * st[j]
        X += static[row, 2] * f
        Y += static[row, 3] * f
        N += static[row, 4] * f
    for row in range(azim.shape[0]):
        j = int(azim[row, 0])
        f = azim[row, 1] * st[j]
        ca, sa = math.cos(st[j + 1]), math.sin(st[j + 1])
        if write:
            gear[j, 0] = ca
            gear[j, 1] = sa
        fx, fy = f * ca, f * sa
        X += fx
        Y += fy
        N += azim[row, 2] * fy - azim[row, 3] * fx
    return X, Y, N


@njit(cache=True, inline="always")
def propeller_flow(st, props, u, lifts):  # type: ignore[no-untyped-def]
    """The propellers-only ``flow_props`` of :meth:`ActuatorSet.flow_kernel` over the rows of
    :meth:`ActuatorSet.propeller_flow_table` (an array); each thrust into ``lifts``."""
    X = 0.0
    Y = 0.0
    K = 0.0
    N = 0.0
    au = abs(u)
    for row in range(props.shape[0]):
        j = int(props[row, 0])
        kp, kn, quad, kua, dep, iu50 = (
            props[row, 1], props[row, 2], props[row, 3], props[row, 4], props[row, 5],
            props[row, 6],
        )  # fmt: skip
        c, s, mn, mk = props[row, 7], props[row, 8], props[row, 9], props[row, 10]
        a = st[j]
        g = kp if a >= 0.0 else kn
        aa = abs(a)
        f = (g * aa if quad != 0.0 else g) * a - kua * aa * u
        if dep != 0.0:
            xu = au * iu50
            xu *= xu
            f *= 1.0 - dep * xu * math.exp(1.0 - xu)
        X += c * f
        Y += s * f
        K += mk * f
        N += mn * f
        lifts[row] = f
    return X, Y, K, N


@njit(cache=True, inline="always")
def grid_at(t, inv_dt, k0, chunk, clamp):  # type: ignore[no-untyped-def]
    """A grid process at ``t`` from its chunk (``GridPair._interp``; Wind's ``at`` clamps the
    speed at 0); ``ok`` False where ``t`` lies past the chunk."""
    x = t * inv_dt
    k = int(x)
    i = k - k0
    if i < 0 or i >= chunk.shape[1] - 1:
        return False, 0.0, 0.0
    f = x - k
    a0, b0 = chunk[0, i], chunk[1, i]
    speed = a0 + f * (chunk[0, i + 1] - a0)
    if clamp and not speed > 0.0:
        speed = 0.0
    return True, speed, b0 + f * (chunk[1, i + 1] - b0)


@njit(cache=True, inline="always")
def _row_at(t, inv_dt, g0, g1, i):  # type: ignore[no-untyped-def]
    """Env ``i``'s process at ``t`` from its sample rows (``GridBatch.at``, one env)."""
    x = t * inv_dt
    k = int(x)
    f = x - k
    a0, b0 = g0[i, k], g1[i, k]
    return a0 + f * (g0[i, k + 1] - a0), b0 + f * (g1[i, k + 1] - b0)


# ---- the loop ------------------------------------------------------------------------------
#: layout of run3's float parameters ``fp`` (after the plant's 30 and the wind load's 12)
_FP_PLANT, _FP_WIND = 0, 30
_FP = 42
#: hh, h, m_q, I_q, wind mode/V/beta/1/dt/k0, current mode/V/beta/1/dt/k0, external X/Y/N,
#: mj_thrust, wave drift on/1/dt/k0/beta_p/k_x/k_y/k_n
_FP_SIZE = _FP + 25


@njit(cache=True)
def run3(  # type: ignore[no-untyped-def]
    mj_step, mp, dp, n, stop_on_contact, t0, ncon,
    qpos, qvel, qacc, act, ctrl, qfrc, gain, gear,
    fp, varying, lateral, static, azim, props, servos, servo_cmd, hits, rlims, rl_cmd,
    wind_chunk, current_chunk, drift_chunk, state, out,
):  # fmt: skip
    """``n`` physics steps of the ``prepare3`` closure and ``mj_step`` (module docstring).

    ``state`` (int64): [0] ramping flag in and out, [1] steps taken out, [2] chunk index
    needed out. ``out`` (float64): the loads of the last step (8), the flow force X, Y, K, N
    and each flow thrust; on divergence t, nu, nu_dot. Returns a code (``OK``, ...).
    """
    kp = fp[_FP_PLANT:_FP_WIND]
    kw = fp[_FP_WIND:_FP]
    hh, h, mq, iq = fp[_FP], fp[_FP + 1], fp[_FP + 2], fp[_FP + 3]
    w_mode, w_V, w_b, w_inv, w_k0 = fp[_FP + 4], fp[_FP + 5], fp[_FP + 6], fp[_FP + 7], fp[_FP + 8]
    c_mode, c_V, c_b, c_inv, c_k0 = (
        fp[_FP + 9], fp[_FP + 10], fp[_FP + 11], fp[_FP + 12], fp[_FP + 13]
    )  # fmt: skip
    ex0, ey0, en0, mj_thrust = fp[_FP + 14], fp[_FP + 15], fp[_FP + 16], fp[_FP + 17] != 0.0
    d_on, d_inv, d_k0, d_beta, d_kx, d_ky, d_kn = (
        fp[_FP + 18] != 0.0, fp[_FP + 19], int(fp[_FP + 20]), fp[_FP + 21], fp[_FP + 22],
        fp[_FP + 23], fp[_FP + 24],
    )  # fmt: skip
    n_flow = props.shape[0]
    lifts = out[12 : 12 + n_flow]
    t = t0
    for i in range(n):
        psi = qpos[2]
        w0, w1, w2 = qvel[0], qvel[1], qvel[2]
        a0, a1, a2 = qacc[0], qacc[1], qacc[2]
        xd, yd, r = w0 + hh * a0, w1 + hh * a1, w2 + hh * a2
        c, s = math.cos(psi), math.sin(psi)
        u = c * xd + s * yd
        v = c * yd - s * xd
        # the disturbances first: a missing chunk returns before anything is written
        if w_mode == 1.0:
            ok, vw, bw = grid_at(t, w_inv, int(w_k0), wind_chunk, True)
            if not ok:
                state[1] = i
                state[2] = int(t * w_inv) // CHUNK
                return NEED_WIND
        else:
            vw, bw = w_V, w_b
        if c_mode == 2.0:
            ok, vc, bc = grid_at(t, c_inv, int(c_k0), current_chunk, False)
            if not ok:
                state[1] = i
                state[2] = int(t * c_inv) // CHUNK
                return NEED_CURRENT
        else:
            vc, bc = c_V, c_b
        if d_on:  # the drift energy E(t) on its grid (Waves.drift_load)
            ok, e, _ = grid_at(t, d_inv, d_k0, drift_chunk, False)
            if not ok:
                state[1] = i
                state[2] = int(t * d_inv) // CHUNK
                return NEED_DRIFT
        else:
            e = 0.0
        if mj_thrust:
            tx, ty, tn = thrust3(act, varying, lateral, static, azim, gain, gear, True)
        else:
            tx = ty = tn = 0.0
        if w_mode >= 0.0:
            wx, wy, wn = wind_load(kw, psi, u, v, vw, bw)
        else:
            wx = wy = wn = 0.0
        if c_mode > 0.0:
            uc = vc * math.cos(bc - psi)
            vcb = vc * math.sin(bc - psi)
        else:
            uc = vcb = 0.0
        if d_on:
            b = d_beta - psi
            cb, sb = math.cos(b), math.sin(b)
            dy_ = d_ky * sb * abs(sb) * e
            dx_ = d_kx * cb * abs(cb) * e
            dn_ = d_kn * cb * dy_
        else:
            dx_ = dy_ = dn_ = 0.0
        ex, ey, en = ex0, ey0, en0
        for row in range(servos.shape[0]):  # each servo's rate, towards its command, limited
            k = int(servos[row, 0])
            j = int(servos[row, 1])
            rate, tc = servos[row, 2], servos[row, 3]
            w = (servo_cmd[k] - act[j]) / (tc if tc > 0.0 else h)
            if w > rate:
                w = rate
                hits[k] = 1
            elif w < -rate:
                w = -rate
                hits[k] = 1
            else:
                hits[k] = 0
            ctrl[j] = w
        if rlims.shape[0] > 0 and state[0] != 0:  # the rate-limited lags' commands
            active = False
            for row in range(rlims.shape[0]):
                k = int(rlims[row, 0])
                j = int(rlims[row, 1])
                band, step = rlims[row, 2], rlims[row, 3]
                c_, a_ = rl_cmd[k], act[j]
                if c_ - a_ > band:
                    x_ = a_ + step
                    c_ = c_ if c_ < x_ else x_  # Python's min(x_, c_)
                    active = True
                elif a_ - c_ > band:
                    x_ = a_ - step
                    c_ = c_ if c_ > x_ else x_  # Python's max(x_, c_)
                    active = True
                ctrl[j] = c_
            if not active:
                state[0] = 0
        if n_flow > 0:
            fl0, fl1, fl2, fl3 = propeller_flow(act, props, u - uc, lifts)
            ex += fl0
            ey += fl1
            en += fl3
            out[8], out[9], out[10], out[11] = fl0, fl1, fl2, fl3
        ud, vd, rd = accel3(
            kp, u, v, r, tx + (wx + dx_ + ex), ty + (wy + dy_ + ey), tn + (wn + dn_ + en), uc, vcb
        )
        if not (math.isfinite(ud + vd + rd) and abs(u) + abs(v) < 50.0 and abs(r) < 10.0):
            out[0], out[1], out[2], out[3] = t, u, v, r
            out[4], out[5], out[6] = ud, vd, rd
            state[1] = i
            return DIVERGED
        bx = ud - r * v
        by = vd + r * u
        qfrc[0] = mq * (c * bx - s * by) - (c * tx - s * ty)
        qfrc[1] = mq * (s * bx + c * by) - (s * tx + c * ty)
        qfrc[2] = iq * rd - tn
        out[0], out[1], out[2], out[3] = wx, wy, wn, dx_
        out[4], out[5], out[6], out[7] = dy_, dn_, uc, vcb
        _call(mj_step, mp, dp)
        t += h
        if stop_on_contact and ncon[0] != 0:
            state[1] = i + 1
            return OK
    state[1] = n
    return OK


@njit(cache=True)
def run_batched3(  # type: ignore[no-untyped-def]
    k, fp, q, qv, qa, act, cmd, lo, hi, alpha, rl_band, rl_step, servo, rate, servo_t, integ,
    bounded, varying, lateral, static, azim, props, aero, t, w_inv, w0, w1, c_inv, c0, c1,
):  # fmt: skip
    """``k`` steps of :class:`~shipgym.envs.batchphysics.BatchedPhysics` (its module
    docstring), hull by hull with the kernels of :func:`run3`: the accelerations as the single
    physics' ``prepare3`` computes them, then the batched physics' Euler update of the
    actuator states, ``qvel`` and ``qpos`` (in place). Each hull's wind and current come from
    its rows of samples (``GridBatch.rows_until``: 1/dt, two channels) at its time ``t``
    (advanced in place, ``t += h`` per step), interpolated as ``GridBatch.at`` does; ``aero``
    gates each hull's wind load; ``fp[_FP + 9] > 0`` says there is a current."""
    kp = fp[_FP_PLANT:_FP_WIND]
    kw = fp[_FP_WIND:_FP]
    hh, h = fp[_FP], fp[_FP + 1]
    current = fp[_FP + 9] > 0.0
    n = q.shape[1]
    nc = act.shape[0]
    lifts = np.empty(props.shape[0])
    no_gain = np.zeros((1, 2))  # thrust3 writes no MuJoCo gains here
    for _j in range(k):
        for i in range(n):
            ti = t[i]
            st = act[:, i]
            psi = q[2, i]
            xd, yd, r = qv[0, i] + hh * qa[0, i], qv[1, i] + hh * qa[1, i], qv[2, i] + hh * qa[2, i]
            c, s = math.cos(psi), math.sin(psi)
            u = c * xd + s * yd
            v = c * yd - s * xd
            if current:
                vc, bc = _row_at(ti, c_inv[i], c0, c1, i)
                d = bc - psi
                uc = vc * math.cos(d)
                vcb = vc * math.sin(d)
            else:
                uc = vcb = 0.0
            tx, ty, tn = thrust3(st, varying, lateral, static, azim, no_gain, no_gain, False)
            if aero[i] != 0.0:
                vw, bw = _row_at(ti, w_inv[i], w0, w1, i)
                vw = vw if vw > 0.0 else 0.0  # np.maximum(V_w, 0)
                wx, wy, wn = wind_load(kw, psi, u, v, vw, bw)
            else:
                wx = wy = wn = 0.0
            ex = ey = en = 0.0
            if props.shape[0] > 0:
                fl0, fl1, _fl2, fl3 = propeller_flow(st, props, u - uc, lifts)
                ex += fl0
                ey += fl1
                en += fl3
            ud, vd, rd = accel3(
                kp, u, v, r, tx + (wx + 0.0 + ex), ty + (wy + 0.0 + ey), tn + (wn + 0.0 + en),
                uc, vcb,
            )  # fmt: skip
            bx = ud - r * v
            by = vd + r * u
            a0 = c * bx - s * by
            a1 = s * bx + c * by
            # the actuator states (MuJoCo's filterexact lags, servos, integrators)
            for ch in range(nc):
                a_, c_ = st[ch], cmd[ch, i]
                gap = c_ - a_
                eff = c_
                if gap > rl_band[ch]:
                    x_ = a_ + rl_step[ch]
                    eff = x_ if x_ < c_ else c_
                if -gap > rl_band[ch]:
                    x_ = a_ - rl_step[ch]
                    eff = x_ if x_ > c_ else c_
                new = a_ + alpha[ch] * (eff - a_)
                if servo[ch]:
                    wr = (c_ - a_) / servo_t[ch]
                    wr = -rate[ch] if wr < -rate[ch] else (rate[ch] if wr > rate[ch] else wr)
                    new = a_ + h * wr
                if integ[ch]:
                    new = a_ + h * c_
                if bounded[ch]:
                    new = hi[ch] if new > hi[ch] else (lo[ch] if new < lo[ch] else new)
                act[ch, i] = new
            qa[0, i], qa[1, i], qa[2, i] = a0, a1, rd
            qv[0, i] += h * a0
            qv[1, i] += h * a1
            qv[2, i] += h * rd
            q[0, i] += h * qv[0, i]
            q[1, i] += h * qv[1, i]
            q[2, i] += h * qv[2, i]
            t[i] = ti + h
