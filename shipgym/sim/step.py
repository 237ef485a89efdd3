r"""The one physics step of shipgym: N >= 1 hulls of one vessel, compiled once.

Public names: ``run``, ``HullBatch``, ``SimulationDiverged``, ``OK``, ``NEED``, ``DIVERGED``,
``MUJOCO``, ``LEAPFROG``, ...
Sources: Blendermann (1994); Tomera (2014).

Design notes: docs/design/sim.step.md.
"""

from __future__ import annotations

import ctypes
import math
from pathlib import Path
from typing import Any

import numpy as np
from numba import carray, prange

from shipgym._jit import (
    _DISABLED,
    ACCEL_SIG,
    ROWS_SIG,
    accel_at,
    address,
    entry,
    njit,
    rows_at,
    threads_ok,
    use_threads,
)
from shipgym.disturbances._grid import load_windows
from shipgym.disturbances.wind import blendermann_load
from shipgym.dynamics.actuators import tau_of_table
from shipgym.sim._mujoco import mujoco

__all__ = [
    "run",
    "HullBatch",
    "SimulationDiverged",
    "OK",
    "NEED",
    "DIVERGED",
    "MUJOCO",
    "LEAPFROG",
    "EVALUATE",
    "mj_step_address",
]

#: return codes of :func:`run` (``RESET``: MuJoCo found a bad state and reset it)
OK, NEED, DIVERGED, RESET = 0, 1, 2, 3
#: integrators (and EVALUATE: the joint acceleration of the state, nothing stepped)
MUJOCO, LEAPFROG, EVALUATE = 0, 1, 2
#: process slots: wind, current, wave drift
WIND, CURRENT, DRIFT = 0, 1, 2
#: process modes: none, constant, sampled on a grid
OFF, CONSTANT, SAMPLED = 0, 1, 2
#: actuator channel dynamics codes (columns of the channel table, :meth:`HullBatch.channels`)
LAG, SERVO, INTEGRATOR = 0, 1, 2

#: bounds beyond which the simulation is declared diverged (m/s, rad/s, rad): far above
#: anything a displacement ship reaches (the Blue Lady: 1.6 m/s; a tanker: 8 m/s).
MAX_SPEED = 50.0
MAX_RATE = 10.0
MAX_ROLL = 1.2


#: the smallest batch stepped in ranges of hulls on Numba's threads (:func:`run_threads`);
#: smaller ones step on the calling thread, where waking the threads costs more than it saves
PARALLEL_MIN = 128


#: the most physics steps one call may take (5.8 days at 0.05 s): a larger request is a
#: mistake, not a simulation (it would hold the process for hours)
MAX_STEPS = 10_000_000

_BADQACC = int(mujoco.mjtWarning.mjWARN_BADQACC)
_BADQVEL = int(mujoco.mjtWarning.mjWARN_BADQVEL)
_BADQPOS = int(mujoco.mjtWarning.mjWARN_BADQPOS)


class SimulationDiverged(RuntimeError):
    """The simulation produced a non-finite or physically absurd state; it was stopped."""


def diverged(t: float, nu: Any, nud: Any) -> None:
    """Raise :class:`SimulationDiverged` for the state ``nu``, ``nu_dot`` at time ``t``."""
    raise SimulationDiverged(
        f"simulation diverged at t = {t:.3f} s: nu = ({', '.join(f'{x:.4g}' for x in nu)})"
        f", nu_dot = ({', '.join(f'{x:.4g}' for x in nud)}); check the plant parameters, "
        "the timestep and the applied forces"
    )


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


def _load_mj_step() -> Any:
    here = Path(mujoco.__file__).parent
    libs = sorted(here.glob("libmujoco.so*")) + sorted(here.glob("libmujoco*.dylib"))
    if not libs:
        raise OSError(f"no libmujoco shared library next to {here}")
    f = ctypes.CDLL(str(libs[0])).mj_step
    f.argtypes = [ctypes.c_void_p, ctypes.c_void_p]
    f.restype = None
    return f


_MJ_STEP = _load_mj_step()


def mj_step_address() -> int:
    """The address of MuJoCo's C ``mj_step`` in the library the ``mujoco`` package loaded (an
    int argument keeps the compiled loop cacheable across processes)."""
    return int(ctypes.cast(_MJ_STEP, ctypes.c_void_p).value or 0)


try:
    from llvmlite import ir
    from numba import types
    from numba.extending import intrinsic

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

    @intrinsic
    def _load(typingctx, addr, k):  # type: ignore[no-untyped-def]
        """The float64 at ``addr + 8 k`` (a field of an ``mjData``)."""
        sig = types.float64(types.intp, types.intp)

        def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
            ptr = builder.inttoptr(args[0], ir.DoubleType().as_pointer())
            return builder.load(builder.gep(ptr, [args[1]]))

        return sig, codegen

    @intrinsic
    def _store(typingctx, addr, k, value):  # type: ignore[no-untyped-def]
        """Write ``value`` to the float64 at ``addr + 8 k``."""
        sig = types.void(types.intp, types.intp, types.float64)

        def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
            ptr = builder.inttoptr(args[0], ir.DoubleType().as_pointer())
            builder.store(args[2], builder.gep(ptr, [args[1]]))
            return context.get_dummy_value()

        return sig, codegen

    @intrinsic
    def _load_i32(typingctx, addr):  # type: ignore[no-untyped-def]
        """The int32 at ``addr`` (``mjData.ncon``), as an int64."""
        sig = types.int64(types.intp)

        def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
            ptr = builder.inttoptr(args[0], ir.IntType(32).as_pointer())
            return builder.sext(builder.load(ptr), ir.IntType(64))

        return sig, codegen

    @intrinsic
    def _f8p(typingctx, addr):  # type: ignore[no-untyped-def]
        """The address ``addr`` as a float64 pointer (for ``numba.carray``)."""
        sig = types.CPointer(types.float64)(types.int64)

        def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
            return builder.inttoptr(args[0], ir.DoubleType().as_pointer())

        return sig, codegen

    @intrinsic
    def _i8p(typingctx, addr):  # type: ignore[no-untyped-def]
        """The address ``addr`` as an int64 pointer (for ``numba.carray``)."""
        sig = types.CPointer(types.int64)(types.int64)

        def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
            return builder.inttoptr(args[0], ir.IntType(64).as_pointer())

        return sig, codegen

except ImportError:  # pragma: no cover - numba is a core dependency
    raise


@njit(inline="always")
def grid_at(t, inv_dt, k0, win, i):  # type: ignore[no-untyped-def]
    """Hull ``i``'s process at time ``t`` from its window ``win[i]`` of samples starting at
    sample ``k0`` (linear interpolation between the samples ``t_k = k / inv_dt``); ``ok``
    False where ``t`` lies past the window."""
    x = t * inv_dt
    k = int(x)
    j = k - k0
    if j < 0 or j >= win.shape[2] - 1:
        return False, 0.0, 0.0
    f = x - k
    a0, b0 = win[i, 0, j], win[i, 1, j]
    return True, a0 + f * (win[i, 0, j + 1] - a0), b0 + f * (win[i, 1, j + 1] - b0)


@njit(inline="always")
def kinematics(q, qv, qa, i, hh, four, linear_kin):  # type: ignore[no-untyped-def]
    """Hull ``i``'s body velocity at the whole step ``(u, v, p, r)`` (step 1 of :func:`run`),
    with what the joint acceleration needs: ``phi``, ``cos psi``, ``sin psi``, ``cos phi``,
    ``sin phi`` (1, 0 for 3 DOF or linear kinematics), ``psi_dot``, ``phi_dot``."""
    psi = q[i, 2]
    c, s = math.cos(psi), math.sin(psi)
    xd = qv[i, 0] + hh * qa[i, 0]
    yd = qv[i, 1] + hh * qa[i, 1]
    psid = qv[i, 2] + hh * qa[i, 2]
    if four:
        phi = q[i, 3]
        phid = qv[i, 3] + hh * qa[i, 3]
        cphi, sphi = (1.0, 0.0) if linear_kin else (math.cos(phi), math.sin(phi))
    else:
        phi = 0.0
        phid = 0.0
        cphi, sphi = 1.0, 0.0
    u = c * xd + s * yd
    v = (c * yd - s * xd) / cphi
    return u, v, phid, psid / cphi, phi, c, s, cphi, sphi, psid, phid


@njit
def body_velocities(q, qv, qa, h, four, linear_kin, out):  # type: ignore[no-untyped-def]
    """Every hull's ``(u, v, p, r)`` at the whole step into ``out`` (N, 4) (step 1 of
    :func:`run`, the same code)."""
    for i in range(q.shape[0]):
        u, v, p, r, _phi, _c, _s, _cf, _sf, _psid, _phid = kinematics(
            q, qv, qa, i, 0.5 * h, four, linear_kin
        )
        out[i, 0], out[i, 1], out[i, 2], out[i, 3] = u, v, p, r


@njit(inline="always")
def process_at(mode, t, i, slot, inv_dt, k0, win, const):  # type: ignore[no-untyped-def]
    """Hull ``i``'s process ``slot`` at time ``t``: its constant (``CONSTANT``; zeros for
    ``OFF``) or the interpolation in its window (``SAMPLED``, :func:`grid_at`)."""
    if mode == SAMPLED:
        return grid_at(t, inv_dt[i, slot], k0[i, slot], win, i)
    return True, const[i, slot, 0], const[i, slot, 1]


@njit
def obstacles_touched(x, y, psi, fp, ob, m):  # type: ignore[no-untyped-def]
    """How many of the ``m`` obstacle rectangles ``ob`` (R, 9) the hull's footprint polygon
    ``fp`` (k, 2; body frame, convex) touches at the pose ``(x, y, psi)``. An obstacle row:
    centre ``cx, cy``, unit axes ``ux, uy``, ``vx, vy``, half sizes ``hu, hv`` (m), and
    ``reach``, the largest centre distance at which the footprint can touch it (a
    bounding-circle test first). The separating-axis test of two convex polygons in the
    horizontal plane: MuJoCo's contact of a hull whose height lies within the obstacles'
    (:func:`~shipgym.envs.batchphysics.contact_geometry`)."""
    c, s = math.cos(psi), math.sin(psi)
    k = fp.shape[0]
    px, py = np.empty(k), np.empty(k)
    ready = False
    count = 0
    for j in range(m):
        cx, cy = ob[j, 0], ob[j, 1]
        dx, dy = x - cx, y - cy
        if dx * dx + dy * dy > ob[j, 8] * ob[j, 8]:
            continue
        if not ready:  # the footprint in the world, once
            for e in range(k):
                px[e] = x + c * fp[e, 0] - s * fp[e, 1]
                py[e] = y + s * fp[e, 0] + c * fp[e, 1]
            ready = True
        ux, uy, vx, vy, hu, hv = ob[j, 2], ob[j, 3], ob[j, 4], ob[j, 5], ob[j, 6], ob[j, 7]
        apart = False
        # the rectangle's two axes: the footprint's extent about the centre against the half size
        for ax in range(2):
            nx, ny, half = (ux, uy, hu) if ax == 0 else (vx, vy, hv)
            lo, hi = math.inf, -math.inf
            for e in range(k):
                d = (px[e] - cx) * nx + (py[e] - cy) * ny
                lo = d if d < lo else lo
                hi = d if d > hi else hi
            if lo > half or hi < -half:
                apart = True
                break
        if apart:
            continue
        # the footprint's edge normals: the rectangle's corners against the polygon's extent
        for e in range(k):
            f = e + 1 if e + 1 < k else 0
            nx, ny = py[f] - py[e], px[e] - px[f]  # the outward normal of a ccw polygon's edge
            edge = px[e] * nx + py[e] * ny  # the polygon's largest extent along it
            low = math.inf
            for corner in range(4):
                a = hu if corner == 0 or corner == 3 else -hu
                b = hv if corner < 2 else -hv
                d = (cx + a * ux + b * vx) * nx + (cy + a * uy + b * vy) * ny
                low = d if d < low else low
            if low > edge:
                apart = True
                break
        if not apart:
            count += 1
    return count


@njit
def _hulls(  # type: ignore[no-untyped-def]
    first, end, integrator, stop_on_contact, h,
    mj_step, mps, dps, fields, views, dofs, linear_kin, inertia,
    accel, kh, laws, table, kind_index, chan, kw,
    q, qv, qa, qfrc, act, cmd, t, left, external,
    mode, const, inv_dt, k0, win_w, win_c, win_d, drift_k,
    loads, forces, flags, hits, stopped, status, foot, obst, nob, touch,
):  # fmt: skip
    """Hulls ``first .. end - 1`` of :func:`run`, one after the other: each its ``left[i]`` steps
    and its code in ``status[i, 0]`` (``NEED`` with the process slot and the sample its time
    lies in, ``int(t inv_dt)``, in ``status[i, 1:]``); returns the largest code."""
    worst = OK
    nq = q.shape[1]
    n_ch = chan.shape[0]
    hh = 0.5 * h
    mq, iq, ix = inertia[0], inertia[2], inertia[3]
    acc = accel_at(accel)
    four = dofs == 4
    for i in range(first, end):
        status[i, 0] = OK
        if left[i] <= 0:  # (not stepped: a reset's start of another hull, a masked hull)
            continue
        st = act[i]
        ti = t[i]
        m_w, m_c, m_d = mode[i, 0], mode[i, 1], mode[i, 2]
        tab = table[i]
        while left[i] > 0:
            # 1. the velocity at the whole step
            u, v, p, r, phi, c, s, cphi, sphi, psid, phid = kinematics(
                q, qv, qa, i, hh, four, linear_kin
            )
            psi = q[i, 2]
            # 2. the loads; a missing window returns before anything is written
            ok_w, vw, bw = process_at(m_w, ti, i, WIND, inv_dt, k0, win_w, const)
            ok_c, vc, bc = process_at(m_c, ti, i, CURRENT, inv_dt, k0, win_c, const)
            ok_d, e, _unused = process_at(m_d, ti, i, DRIFT, inv_dt, k0, win_d, const)
            if not (ok_w and ok_c and ok_d):
                slot = WIND if not ok_w else (CURRENT if not ok_c else DRIFT)
                status[i, 0], status[i, 1] = NEED, slot
                status[i, 2] = int(ti * inv_dt[i, slot])
                break
            vw = vw if vw > 0.0 else 0.0  # a gust's speed never below 0
            if m_w != OFF:
                wx, wy, wn = blendermann_load(kw, psi, u, v, vw, bw)
            else:
                wx = wy = wn = 0.0
            if m_c != OFF:
                uc = vc * math.cos(bc - psi)
                vcb = vc * math.sin(bc - psi)
            else:
                uc = vcb = 0.0
            if m_d == SAMPLED:
                b = drift_k[i, 0] - psi
                cb, sb = math.cos(b), math.sin(b)
                dy_ = drift_k[i, 2] * sb * abs(sb) * e
                dx_ = drift_k[i, 1] * cb * abs(cb) * e
                dn_ = drift_k[i, 3] * cb * dy_
            else:
                dx_ = dy_ = dn_ = 0.0
            ur = u - uc
            vr = v - vcb
            tx, ty, tk, tn = tau_of_table(tab, laws, kind_index, st, ur, vr, p, r, forces[i],
                                          flags[i])  # fmt: skip
            # 3. the hull's acceleration
            ud, vd, pd, rd = acc(
                kh, u, v, p, r, phi,
                tx + wx + dx_ + external[i, 0], ty + wy + dy_ + external[i, 1],
                tk + external[i, 2], tn + wn + dn_ + external[i, 3], uc, vcb,
            )  # fmt: skip
            if not (
                math.isfinite(ud + vd + pd + rd)
                and abs(u) + abs(v) < MAX_SPEED
                and abs(r) + abs(p) < MAX_RATE
                and abs(phi) < MAX_ROLL
            ):
                status[i, 0] = DIVERGED
                lo = loads[i]
                lo[0], lo[1], lo[2], lo[3], lo[4] = ti, u, v, p, r
                lo[5], lo[6], lo[7] = ud, vd, rd
                break
            if four:  # qacc = J nu_dot + J_dot nu (Fossen's 4-DOF kinematics)
                sv, cv = s * v, c * v
                a0 = c * ud - s * cphi * vd - s * u * psid - cphi * cv * psid + sphi * sv * phid
                a1 = s * ud + c * cphi * vd + c * u * psid - cphi * sv * psid - sphi * cv * phid
                a2 = cphi * rd - sphi * r * phid
            else:  # qacc = R(psi)(nu_dot + r S nu), S nu = [-v, u, 0]
                bx = ud - r * v
                by = vd + r * u
                a0 = c * bx - s * by
                a1 = s * bx + c * by
                a2 = rd
            lo = loads[i]
            lo[0], lo[1], lo[2], lo[3] = wx, wy, wn, dx_
            lo[4], lo[5], lo[6], lo[7] = dy_, dn_, uc, vcb
            if integrator == EVALUATE:
                qa[i, 0], qa[i, 1], qa[i, 2] = a0, a1, a2
                if four:
                    qa[i, 3] = pd
                left[i] = 0
                break
            # 4. the actuator states
            for ch in range(n_ch):
                a_, c_ = st[ch], cmd[i, ch]
                code = chan[ch, 0]
                if code == LAG:
                    eff = c_
                    if c_ - a_ > chan[ch, 4]:
                        x_ = a_ + chan[ch, 5]
                        eff = x_ if x_ < c_ else c_
                    elif a_ - c_ > chan[ch, 4]:
                        x_ = a_ - chan[ch, 5]
                        eff = x_ if x_ > c_ else c_
                    new = a_ + chan[ch, 3] * (eff - a_)
                elif code == SERVO:
                    rate = chan[ch, 6]
                    w = (c_ - a_) / chan[ch, 7]
                    if w > rate:
                        w = rate
                        hits[i, ch] = 1
                    elif w < -rate:
                        w = -rate
                        hits[i, ch] = 1
                    else:
                        hits[i, ch] = 0
                    new = a_ + h * w
                else:
                    new = a_ + h * c_
                if chan[ch, 8] != 0.0:
                    lo_, hi_ = chan[ch, 1], chan[ch, 2]
                    new = hi_ if new > hi_ else (lo_ if new < lo_ else new)
                st[ch] = new
            # 5. the integration
            left[i] -= 1
            ti += h
            if integrator == MUJOCO:
                qfrc[i, 0] = mq * a0
                qfrc[i, 1] = mq * a1
                qfrc[i, 2] = iq * a2
                if four:
                    qfrc[i, 3] = ix * pd
                fp, fv, fa, ff = fields[i, 0], fields[i, 1], fields[i, 2], fields[i, 3]
                if not views:  # (views: the arrays are the mjData's own)
                    for k in range(nq):
                        _store(fp, k, q[i, k])
                        _store(fv, k, qv[i, k])
                        _store(ff, k, qfrc[i, k])
                _call(mj_step, mps[i], dps[i])
                if not views:
                    for k in range(nq):
                        q[i, k] = _load(fp, k)
                        qv[i, k] = _load(fv, k)
                        qa[i, k] = _load(fa, k)
                # MuJoCo resets a bad state and only counts a warning: stop the hull
                if _load_i32(fields[i, 5]) + _load_i32(fields[i, 6]) + _load_i32(fields[i, 7]):
                    status[i, 0] = RESET
                    break
                if stop_on_contact and _load_i32(fields[i, 4]) != 0:
                    stopped[i] = left[i]
                    left[i] = 0
            else:
                # obstacles (a harbour's quays): touched at the step's start, as mj_step finds
                # its contacts before it integrates; the hull stops after this step
                touched = 0
                if stop_on_contact and nob[i] > 0:
                    touched = obstacles_touched(q[i, 0], q[i, 1], q[i, 2], foot, obst[i], nob[i])
                    touch[i] = touched
                qa[i, 0], qa[i, 1], qa[i, 2] = a0, a1, a2
                if four:
                    qa[i, 3] = pd
                for k in range(q.shape[1]):
                    qv[i, k] += h * qa[i, k]
                    q[i, k] += h * qv[i, k]
                if touched:
                    stopped[i] = left[i]
                    left[i] = 0
        t[i] = ti
        worst = status[i, 0] if status[i, 0] > worst else worst
    return worst


@njit(inline="always")
def _arrays(p):  # type: ignore[no-untyped-def]
    """:func:`run`'s arrays from the table ``p`` of their shapes and addresses
    (:meth:`HullBatch.table_of_arrays`), in :func:`_hulls`' order after ``h``."""
    n, nq, nc, na, kt, nkh, nl, nkw = p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]
    ww, wc, wd = p[8], p[9], p[10]
    f, i = _f8p, _i8p
    return (
        p[14], carray(i(p[15]), n), carray(i(p[16]), n), carray(i(p[17]), (n, 8)),
        p[48] != 0, p[11], p[12] != 0, carray(f(p[18]), 4),
        p[13], carray(f(p[19]), nkh), carray(i(p[20]), nl), carray(f(p[21]), (n, na, kt)),
        carray(i(p[22]), na), carray(f(p[23]), (nc, 9)), carray(f(p[24]), nkw),
        carray(f(p[25]), (n, nq)), carray(f(p[26]), (n, nq)), carray(f(p[27]), (n, nq)),
        carray(f(p[28]), (n, nq)), carray(f(p[29]), (n, nc)), carray(f(p[30]), (n, nc)),
        carray(f(p[31]), n), carray(i(p[32]), n), carray(f(p[33]), (n, 4)),
        carray(i(p[34]), (n, 3)), carray(f(p[35]), (n, 3, 2)), carray(f(p[36]), (n, 3)),
        carray(i(p[37]), (n, 3)), carray(f(p[38]), (n, 2, ww)), carray(f(p[39]), (n, 2, wc)),
        carray(f(p[40]), (n, 2, wd)), carray(f(p[41]), (n, 4)), carray(f(p[42]), (n, 8)),
        carray(f(p[43]), (n, na)), carray(f(p[44]), (n, na)), carray(i(p[45]), (n, nc)),
        carray(i(p[46]), n), carray(i(p[47]), (n, 3)),
        carray(f(p[51]), (p[49], 2)), carray(f(p[52]), (n, p[50], 9)), carray(i(p[53]), n),
        carray(i(p[54]), n),
    )  # fmt: skip


@njit
def run(first, end, integrator, stop_on_contact, h, p):  # type: ignore[no-untyped-def]
    """Advance each hull ``i`` of ``first .. end - 1`` by ``left[i]`` physics steps (module
    docstring), one after the other: a large batch runs ranges of hulls on Numba's threads
    (:func:`run_threads`), each hull the same floats.

    Args:
        first, end: the hulls stepped (int64).
        integrator: :data:`MUJOCO` (each hull its own ``mjData``), :data:`LEAPFROG`, or
            :data:`EVALUATE` (only ``qa`` and the read-outs of the state written: the start
            of a run).
        stop_on_contact: stop a hull after the step in which MuJoCo finds a contact.
        h: the step (s).
        p: int64, the shapes and addresses of the batch's arrays
            (:meth:`HullBatch.table_of_arrays`: passing one table instead of 30 arrays saves
            the microseconds Numba spends unboxing each array of each call). They are, N
            hulls, nv joints, nc channels, na actuators, all C-contiguous float64 unless said:

            - mj_step, mps, dps: the address of MuJoCo's ``mj_step``; (N,) int64 the
              addresses of each hull's ``mjModel`` and ``mjData`` (``mujoco`` only);
            - fields: (N, 8) int64 the addresses of each hull's ``qpos``, ``qvel``,
              ``qacc``, ``qfrc_applied``, ``ncon`` and the bad-position, -velocity and
              -acceleration warning counters in its ``mjData`` (``mujoco`` only): the loop
              writes ``q``, ``qv`` and ``qfrc`` there before ``mj_step`` and reads ``q``,
              ``qv`` and ``qa`` back after it (a no-op where the arrays are views on the
              ``mjData``, as for :class:`~shipgym.envs.physics.VesselPhysics`: ``views``,
              the last entry of ``p``);
            - dofs: 3 or 4; linear_kin: the 4-DOF hull's linear kinematics (``cos phi = 1``);
            - inertia: MuJoCo's joint-space inertia ``(m, m, I_z, I_x)``;
            - accel: the address of the hull family's compiled acceleration
              (:func:`shipgym._jit.address`); kh: its constants;
            - laws, table, kind_index: the addresses of the actuator force laws (int64);
              (N, na, k) each hull's row of constants per actuator (hulls of one vessel may
              differ in them: a rudder moved); each row's law
              (:meth:`~shipgym.dynamics.actuators.ActuatorSet.law_table`);
            - chan: (nc, 9) channel dynamics: code, lower, upper, alpha = 1 - exp(-h/T),
              rate-limit band, rate-limit step, servo rate, servo time constant, bounded;
            - kw: the wind load's constants
              (:meth:`~shipgym.disturbances.wind.WindLoad.kernel_constants`);
            - q, qv, qa, qfrc: (N, nv) joint positions, half-step velocities, accelerations,
              and the applied force written for MuJoCo;
            - act, cmd: (N, nc) actuator states and commands;
            - t: (N,) each hull's time (s); left: (N,) int64 steps still to take, counted
              down;
            - external: (N, 4) a held external load ``[X, Y, K, N]`` (N, N m);
            - mode: (N, 3) int64 process modes (wind, current, drift: ``OFF``,
              ``CONSTANT``, ``SAMPLED``); const: (N, 3, 2) constant values (speed,
              direction); inv_dt, k0: (N, 3) sample rate (1/s) and the first sample of each
              window (int64); win_w, win_c, win_d: (N, 2, W) the windows of samples;
            - drift_k: (N, 4) the drift's ``beta_p`` (rad), ``k_x``, ``k_y``, ``k_n``;
            - loads: (N, 8) out: the last step's wind X, Y, N, drift X, Y, N, current
              u_c, v_c;
            - forces, flags: (N, na) out: each actuator's force reading (N) and stall flag;
            - hits: (N, nc) int64 out: 1 where a servo ran at its rate limit in the last
              step;
            - stopped: (N,) int64 out: the steps a contact stop left untaken (``mujoco``);
            - status: (N, 3) int64 out: each hull's code, and the process and the sample it
              needs (``NEED``); a hull that diverged (``DIVERGED``) has its t, nu, nu_dot in
              ``loads[i]``; ``RESET``: MuJoCo reset the hull's bad state. Every hull runs on
              whatever another one needs.

    Returns:
        The largest code of the hulls: ``OK``, ``NEED``, ``DIVERGED`` or ``RESET``.
    """
    return _hulls(first, end, integrator, stop_on_contact, h, *_arrays(p))


@njit(parallel=True)
def run_threads(at, integrator, stop_on_contact, h, p):  # type: ignore[no-untyped-def]
    """:func:`run` (compiled at the address ``at``, :func:`shipgym._jit.address`) on ranges of
    the hulls on Numba's threads: the one compiled loop, called through its address (a call
    of the function itself would compile the loop again into this one), each hull the floats
    it gets alone; for large batches called from the main thread (:data:`PARALLEL_MIN`)."""
    go = rows_at(at)
    n = p[0]
    chunks = min(n, 64)  # a few chunks a thread: hulls of unequal work balance
    size = (n + chunks - 1) // chunks
    codes = np.zeros(chunks, dtype=np.int64)
    for c in prange(chunks):
        codes[c] = go(min(c * size, n), min((c + 1) * size, n), integrator, stop_on_contact, h, p)
    return codes.max()


@njit
def actuator_rows(tab, laws, kinds, st, vel, loads, out, forces):  # type: ignore[no-untyped-def]
    """Hull ``i``'s actuator load ``(X, Y, K, N)`` into ``out[i]`` and its actuators' forces
    into ``forces[i]``: :func:`~shipgym.dynamics.actuators.tau_of_table` at its states
    ``st[i]`` and its velocity through the water ``(u - u_c, v - v_c, p, r)`` (``vel``: the
    body velocities, ``loads``: the last step's current in columns 6-7); ``tab`` (N or 1, na,
    k): each hull's rows, or one set for all."""
    flags = np.zeros(kinds.shape[0])
    own = tab.shape[0] > 1
    for i in range(st.shape[0]):
        u, v, p, r = vel[i, 0], vel[i, 1], vel[i, 2], vel[i, 3]
        X, Y, K, N = tau_of_table(tab[i if own else 0], laws, kinds, st[i], u - loads[i, 6],
                                  v - loads[i, 7], p, r, forces[i], flags)  # fmt: skip
        out[i, 0], out[i, 1], out[i, 2], out[i, 3] = X, Y, K, N


@njit
def readout_rows(  # type: ignore[no-untyped-def]
    q, qv, qa, h, four, linear_kin, nu, tab, laws, kinds, act, cmd, holds, loads, forces,
    btab, blaws, bkinds, model, at_command,
):  # fmt: skip
    """What an env reads of the hulls' actuators now, in one call: the body velocities into
    ``nu`` (:func:`body_velocities`), each hull's own laws at its states ``act``
    (:func:`actuator_rows`: the actuators' forces into ``forces``), ``[X, Y, N]`` (N, 3) of
    the laws ``btab, blaws, bkinds`` (a bollard model's, one set for all; ``btab`` of 0
    rows: the own laws, the same call) at the same states into ``model``, and (where
    ``at_command`` has N rows) of the own laws at the held commands of the channels of
    ``holds`` (the states elsewhere) into ``at_command``."""
    n = act.shape[0]
    body_velocities(q, qv, qa, h, four, linear_kin, nu)
    out = np.empty((n, 4))
    actuator_rows(tab, laws, kinds, act, nu, loads, out, forces)
    if btab.shape[0] > 0:
        actuator_rows(btab, blaws, bkinds, act, nu, loads, out, np.empty((n, bkinds.shape[0])))
    for i in range(n):
        model[i, 0], model[i, 1], model[i, 2] = out[i, 0], out[i, 1], out[i, 3]
    if at_command.shape[0] > 0:
        st = act.copy()
        for i in range(n):
            for c in range(st.shape[1]):
                if holds[c]:
                    st[i, c] = cmd[i, c]
        actuator_rows(tab, laws, kinds, st, nu, loads, out, np.empty(forces.shape))
        for i in range(n):
            at_command[i, 0], at_command[i, 1], at_command[i, 2] = out[i, 0], out[i, 1], out[i, 3]


@njit
def ncon_rows(fields, out):  # type: ignore[no-untyped-def]
    """Each hull's MuJoCo contact count now (``mjData.ncon`` at ``fields[i, 4]``) into
    ``out`` (N,) int64."""
    for i in range(out.shape[0]):
        out[i] = _load_i32(fields[i, 4])


def channel_table(actuators: Any, h: float) -> np.ndarray:
    """The channel dynamics of :func:`run` ``(nc, 9)`` for the step ``h`` (s): code, lower,
    upper, ``alpha = 1 - exp(-h/T)``, rate-limit band ``rate T`` (inf: none), rate-limit step
    ``rate h / (1 - exp(-h/T))`` (the filter's input that moves the state by exactly ``rate h``
    in one step), servo rate, servo time constant (``h`` for an ideal servo), bounded (1.0)."""
    rows = []
    for c in actuators.channels:
        if c.dynamics == "lag":
            tc = c.time_constant
            alpha = -math.expm1(-h / tc)
            limited = math.isfinite(c.rate)
            band = c.rate * tc if limited else math.inf
            step = c.rate * h / alpha if limited else 0.0
            rows.append((LAG, c.lower, c.upper, alpha, band, step, 0.0, 1.0, 1.0))
        elif c.dynamics == "servo":
            rows.append((SERVO, c.lower, c.upper, 0.0, math.inf, 0.0, c.rate,
                         c.time_constant or h, 1.0))  # fmt: skip
        elif c.dynamics == "integrator":
            rows.append((INTEGRATOR, c.lower, c.upper, 0.0, math.inf, 0.0, 0.0, 1.0, 0.0))
        else:  # pragma: no cover - Channel checks its dynamics
            raise ValueError(f"channel {c.name!r}: unknown dynamics {c.dynamics!r}")
    return np.array(rows, dtype=np.float64).reshape(len(rows), 9)


def hull_kernel(plant: Any) -> tuple[int, np.ndarray]:
    """``(accel, constants)`` of a hull model: the address of its family's compiled
    acceleration (:data:`~shipgym._jit.ACCEL_SIG`) and its constant vector."""
    fn = getattr(type(plant), "accel_kernel", None)
    if fn is None or not callable(getattr(plant, "kernel_constants", None)):
        raise TypeError(
            f"{type(plant).__name__} is not a hull family model: it needs an accel_kernel "
            "(a compiled function of shipgym._jit.ACCEL_SIG) and kernel_constants()"
        )
    k = np.ascontiguousarray(plant.kernel_constants(), dtype=np.float64)
    return address(fn, ACCEL_SIG), k


class HullBatch:
    """The state of N hulls of one vessel and the constants of :func:`run`; :meth:`advance`
    steps them, loading each process's samples as the loop asks for them.

    Args:
        plant: the hull model (a hull family's model: :func:`hull_kernel`).
        actuators: the :class:`~shipgym.dynamics.actuators.ActuatorSet` the plant drives.
        wind_constants: the wind load's constants
            (:meth:`~shipgym.disturbances.wind.WindLoad.kernel_constants`).
        n: number of hulls.
        h: the physics step (s).
        inertia: MuJoCo's joint-space inertia ``(m, m, I_z, I_x)`` (kg, kg, kg m^2, kg m^2).
        integrator: ``"mujoco"`` (each hull its own ``mjData``: ``model`` and ``data`` one
            ``mjModel``/``mjData`` for ``n = 1``, whose arrays become the state's, or
            sequences of ``n``) or ``"leapfrog"``.
    """

    def __init__(
        self,
        plant: Any,
        actuators: Any,
        wind_constants: Any,
        n: int,
        h: float,
        inertia: tuple[float, float, float, float],
        *,
        integrator: str = "leapfrog",
        model: Any = None,
        data: Any = None,
    ) -> None:
        if integrator not in ("mujoco", "leapfrog"):
            raise ValueError(f"integrator must be 'mujoco' or 'leapfrog', got {integrator!r}")
        self.dofs = dofs = int(getattr(plant, "dofs", 3))
        self.n = n
        self.h = float(h)
        self.integrator = integrator
        self.accel, self.kh = hull_kernel(plant)
        self.linear_kin = getattr(plant, "kinematics", "fossen") == "linear"
        table, self.laws, self.kind_index = actuators.law_table()
        self.table = np.repeat(table[None], n, axis=0)  # (N, na, k): set_actuators
        self.chan = channel_table(actuators, self.h)
        self.kw = np.ascontiguousarray(wind_constants, dtype=np.float64)
        self.inertia = np.asarray(inertia, dtype=np.float64)
        nc, na = actuators.n_channels, len(actuators)
        self._sources = (plant, actuators)  # (the laws' addresses again after a pickle)
        self.models: list[Any] = []
        self.datas: list[Any] = []
        if integrator == "mujoco":
            models = list(model) if isinstance(model, (list, tuple)) else [model] * n
            datas = list(data) if isinstance(data, (list, tuple)) else [data]
            if len(datas) != n or len(models) != n or None in models or None in datas:
                raise ValueError(
                    f"the mujoco integrator needs each hull's mjModel and mjData ({n} of each)"
                )
            self.models, self.datas = models, datas
        self._views = integrator == "mujoco" and n == 1
        if not self._views:
            self.q = np.zeros((n, dofs))
            self.qv = np.zeros((n, dofs))
            self.qa = np.zeros((n, dofs))
            self.qfrc = np.zeros((n, dofs))
        self._bind_mujoco()
        self.act = np.zeros((n, nc))
        self.cmd = np.zeros((n, nc))
        self.t = np.zeros(n)
        self.left = np.zeros(n, dtype=np.int64)
        self.external = np.zeros((n, 4))
        self.mode = np.zeros((n, 3), dtype=np.int64)
        self.const = np.zeros((n, 3, 2))
        self.inv_dt = np.zeros((n, 3))
        self.k0 = np.zeros((n, 3), dtype=np.int64)
        self.windows = [np.zeros((n, 2, 2)) for _ in range(3)]
        self.drift_k = np.zeros((n, 4))
        self.processes: list[list[Any]] = [[None] * n for _ in range(3)]
        self.loads = np.zeros((n, 8))
        self.forces = np.zeros((n, na))
        self.flags = np.zeros((n, na))
        self.hits = np.zeros((n, nc), dtype=np.int64)
        self.stopped = np.zeros(n, dtype=np.int64)
        self.status = np.zeros((n, 3), dtype=np.int64)
        self._integ = MUJOCO if integrator == "mujoco" else LEAPFROG
        self._entry: Any = None  # run's compiled entry point for these arguments' types
        self._args: tuple[Any, ...] | None = None  # run's arrays, held while p points at them
        self._p = np.zeros(55, dtype=np.int64)  # their shapes and addresses (table_of_arrays)
        #: the contact check of a leapfrog hull among obstacles (:meth:`set_obstacles`): the
        #: footprint polygon (k, 2) (body frame, m), each hull's obstacle rectangles (n, R, 9)
        #: and their number, and the obstacles each touched at its last step's start
        self.footprint = np.zeros((1, 2))
        self.obstacles = np.zeros((n, 0, 9))
        self.n_obstacles = np.zeros(n, dtype=np.int64)
        self.touching = np.zeros(n, dtype=np.int64)
        self._nu = np.zeros((n, 4))  # body_velocities' output
        self._nu_entry: Any = None
        self._ncon_entry: Any = None
        self._loads_entry: Any = None
        self._readout_entry: Any = None

    def _bind_mujoco(self) -> None:
        """The addresses the loop reads each hull's ``mjData`` at (``mujoco``; again after a
        copy or a pickle: addresses belong to one process and one object), and for one hull
        the state arrays as views on its ``mjData``."""
        n = self.n
        self._mj_step = mj_step_address() if self.datas else 0
        self.mps = np.zeros(n, dtype=np.int64)
        self.dps = np.zeros(n, dtype=np.int64)
        self.fields = np.zeros((n, 8), dtype=np.int64)
        for i, (m, d) in enumerate(zip(self.models, self.datas, strict=True)):
            self.mps[i], self.dps[i] = m._address, d._address
            self.fields[i, :4] = [a.ctypes.data for a in (d.qpos, d.qvel, d.qacc, d.qfrc_applied)]
            self.fields[i, 4] = ncon_view(m, d).ctypes.data
            warn = d.warning.number  # int32 counters, a strided view on mjData
            self.fields[i, 5:] = [
                warn.ctypes.data + k * warn.strides[0] for k in (_BADQPOS, _BADQVEL, _BADQACC)
            ]
        if self._views:  # the hull's own arrays: MuJoCo's state
            d = self.datas[0]
            self.q = d.qpos.reshape(1, -1)
            self.qv = d.qvel.reshape(1, -1)
            self.qa = d.qacc.reshape(1, -1)
            self.qfrc = d.qfrc_applied.reshape(1, -1)
        self._clock = self.datas[0] if self._views else None
        self._args = None

    def __getstate__(self) -> dict[str, Any]:
        """A copy or a pickle keeps the state and rebuilds every address on first use: the
        loop's table (:meth:`table_of_arrays`), the compiled laws', MuJoCo's."""
        state = dict(self.__dict__)
        state.update(
            _args=None,
            _entry=None,
            _nu_entry=None,
            _ncon_entry=None,
            _loads_entry=None,
            _readout_entry=None,
            _p=np.zeros_like(self._p),
        )
        for k in ("q", "qv", "qa", "qfrc"):  # (views on the mjData: rebound to its copy)
            if self._views:
                state[k] = None
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        plant, actuators = self._sources
        self.accel = hull_kernel(plant)[0]
        self.laws = actuators.law_table()[1]
        self._bind_mujoco()

    # ---- disturbances ----------------------------------------------------------------------
    def set_processes(self, i: int, wind: Any, current: Any, waves: Any) -> None:
        """Hull ``i``'s wind (a :class:`~shipgym.disturbances.Wind` or ``None``: no
        aerodynamic load), current (a :class:`~shipgym.disturbances.Current` or ``None``) and
        wave drift (a :class:`~shipgym.disturbances.Waves` or ``None``), each already reset:
        their grids are read from the hull's time on."""
        for slot, proc in ((WIND, wind), (CURRENT, current)):
            self.processes[slot][i] = None
            self.inv_dt[i, slot] = 0.0
            if proc is None:
                self.mode[i, slot] = OFF
                self.const[i, slot] = 0.0
                continue
            const = proc.constant
            if const is not None:
                off = slot == CURRENT and const[0] == 0.0
                self.mode[i, slot] = OFF if off else CONSTANT
                self.const[i, slot] = const
                continue
            self.mode[i, slot] = SAMPLED
            self.processes[slot][i] = proc
            self.inv_dt[i, slot] = proc.sample_rate
            self._load(i, slot, int(self.t[i] * proc.sample_rate))
        drift = None if waves is None else waves.drift_constants
        self.processes[DRIFT][i] = None
        if drift is None:
            self.mode[i, DRIFT] = OFF
            self.drift_k[i] = 0.0
        else:
            self.mode[i, DRIFT] = SAMPLED
            self.processes[DRIFT][i] = waves
            self.drift_k[i] = drift
            self.inv_dt[i, DRIFT] = waves.sample_rate
            self._load(i, DRIFT, int(self.t[i] * waves.sample_rate))

    def _load(self, i: int, slot: int, k: int) -> None:
        """The piece of hull ``i``'s process ``slot`` that holds the sample ``k`` into its
        window (``window(k)``: only that piece is computed, :data:`~shipgym.disturbances.
        _grid.PIECE` samples)."""
        k0, rows = self.processes[slot][i].window(k)
        self._install(i, slot, k0, rows)

    def _install(self, i: int, slot: int, k0: int, rows: np.ndarray) -> None:
        """Hull ``i``'s window of its process ``slot``: the piece ``rows`` from sample ``k0``
        (:meth:`_load`)."""
        rows = rows[:2]
        win = self.windows[slot]
        if win.shape[2] != rows.shape[1]:
            win = np.zeros((self.n, 2, rows.shape[1]))
            win[:] = self.windows[slot][:, :, :1]
            self.windows[slot] = win
            self._args = None
        win[i] = rows
        self.k0[i, slot] = k0

    # ---- state ---------------------------------------------------------------------------
    @property
    def law_table(self) -> tuple[Any, Any, Any]:
        """``(table, laws, kind_index)`` of hull 0's actuators
        (:meth:`~shipgym.dynamics.actuators.ActuatorSet.law_table`)."""
        return self.table[0], self.laws, self.kind_index

    def set_actuators(self, i: int, actuators: Any) -> None:
        """Hull ``i``'s actuator constants from ``actuators``: an
        :class:`~shipgym.dynamics.actuators.ActuatorSet` of the batch's kinds and channels
        whose law rows may differ (a rudder at another position, say).

        Raises:
            ValueError: other kinds or other channel dynamics.
        """
        table, laws, kinds = actuators.law_table()
        if (
            table.shape != self.table.shape[1:]
            or not np.array_equal(laws[kinds], self.laws[self.kind_index])
            or not np.array_equal(channel_table(actuators, self.h), self.chan)
        ):
            raise ValueError(
                "a hull's actuators must be the batch's kinds with the same channel dynamics"
            )
        self.table[i] = table

    def set_pose(self, i: int, eta: Any, nu: Any) -> None:
        """Hull ``i`` at the pose ``eta`` and body velocity ``nu`` (3 DOF: ``[x, y, psi]``,
        ``[u, v, r]``; 4 DOF: Fossen's ``[x, y, phi, psi]``, ``[u, v, p, r]``), at rest in
        acceleration: call :meth:`start` once its processes are set."""
        c, s = math.cos(eta[-1]), math.sin(eta[-1])
        if self.dofs == 3:
            u, v, r = (float(x) for x in nu)
            self.q[i] = eta
            self.qv[i] = (c * u - s * v, s * u + c * v, r)
        else:
            x, y, phi, psi = (float(a) for a in eta)
            u, v, p, r = (float(a) for a in nu)
            cf = 1.0 if self.linear_kin else math.cos(phi)
            self.q[i] = (x, y, psi, phi)
            self.qv[i] = (c * u - s * cf * v, s * u + c * cf * v, r * cf, p)
        self.qa[i] = 0.0

    def reset_hull(
        self, i: int, eta: Any, nu: Any, act: Any, hold: Any, rng: np.random.Generator,
        wind: Any, current: Any, waves: Any, *, aerodynamics: bool, drift: bool,
    ) -> None:  # fmt: skip
        """Start hull ``i`` of an episode: the pose ``eta`` and body velocity ``nu``
        (:meth:`set_pose`), the actuator states ``act`` (the channels in ``hold`` commanded to
        hold them, the others to zero), its clock at 0 and its disturbances reset from
        ``rng`` in a fixed order, one draw each (the wind, the current, the waves: the same
        seed gives the same episode), the wind's load on where ``aerodynamics``, the waves'
        drift where ``drift``; then its leapfrog started (:meth:`start`). The one reset of
        a hull, for the single and the batched physics."""
        if self.datas:
            mujoco.mj_resetData(self.models[i], self.datas[i])
        self.set_pose(i, eta, nu)
        self.act[i] = act
        self.cmd[i] = np.where(hold, act, 0.0)
        self.external[i] = 0.0
        self.t[i] = 0.0
        wind.reset(rng)
        current.reset(rng)
        if waves is not None:
            waves.reset(rng)
        self.set_processes(i, wind if aerodynamics else None, current, waves if drift else None)
        if self.datas:  # MuJoCo's positions and contacts of the start (qacc: set by start)
            d = self.datas[i]
            d.qpos[:] = self.q[i]
            d.qvel[:] = self.qv[i]
            mujoco.mj_forward(self.models[i], d)
        self.start(i)
        self.hits[i] = 0  # nothing stepped yet: no rate limit hit, no stall, no contact
        self.touching[i] = 0
        self.flags[i] = 0.0

    def start(self, i: int) -> None:
        """Start hull ``i``'s leapfrog: ``qacc = a_0`` of its state (:data:`EVALUATE`), then
        ``qvel = v_{-1/2} = v_0 - h/2 a_0``."""
        self.qa[i] = 0.0
        self._advance(EVALUATE, 1, i)
        self.qv[i] -= 0.5 * self.h * self.qa[i]

    def actuator_loads(
        self, st: np.ndarray, table: Any = None, forces: np.ndarray | None = None
    ) -> np.ndarray:
        """``[X, Y, K, N]`` (N, N, N m, N m), (N, 4), of the actuator force laws at the states
        ``st`` (N, nc) and each hull's velocity through the water now (the current of the last
        step): the laws of ``table`` (a ``law_table`` for every hull, e.g. a DP system's
        bollard model) or, ``None``, each hull's own rows; each actuator's own force (N) into
        ``forces`` (N, na) where given. The read-outs of the single and the batched physics."""
        if table is None:
            tab, laws, kinds = self.table, self.laws, self.kind_index
        else:
            tab, laws, kinds = table
            tab = tab if tab.ndim == 3 else tab[None]
        out = np.empty((self.n, 4))
        if forces is None:
            forces = np.empty((self.n, kinds.shape[0]))
        args = (tab, laws, kinds, np.ascontiguousarray(st, dtype=np.float64),
                self.body_velocities(), self.loads, out, forces)  # fmt: skip
        if self._loads_entry is None:  # (the types do not change: found once)
            self._loads_entry = entry(actuator_rows, args)
        self._loads_entry(*args)
        return out

    def readouts(
        self, table: Any, holds: np.ndarray, command: bool
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """``(forces, model, at_command)`` now from one compiled call (:func:`readout_rows`):
        each actuator's force (N) (N, na), ``[X, Y, N]`` (N, 3) of the laws of ``table`` (a
        ``law_table`` for every hull; ``None``: the hulls' own laws) at the actuator states
        and, where ``command``, of the own laws at the held commands of the channels of
        ``holds`` ((nc,) bools; the states elsewhere): the ``X, Y, N`` columns of
        :meth:`actuator_loads` for each, the same floats."""
        n = self.n
        forces, model = np.empty((n, self.kind_index.shape[0])), np.empty((n, 3))
        at_command = np.empty((n if command else 0, 3))
        if table is None:
            btab, blaws, bkinds = self.table[:0], self.laws, self.kind_index
        else:
            btab, blaws, bkinds = table
            btab = btab if btab.ndim == 3 else btab[None]
        args = (self.q, self.qv, self.qa, self.h, self.dofs == 4, self.linear_kin, self._nu,
                self.table, self.laws, self.kind_index, self.act, self.cmd, holds, self.loads,
                forces, btab, blaws, bkinds, model, at_command)  # fmt: skip
        if self._readout_entry is None:  # (the types do not change: found once)
            self._readout_entry = entry(readout_rows, args)
        self._readout_entry(*args)
        return forces, model, at_command if command else None

    def set_obstacles(self, footprint: np.ndarray, i: int, rects: np.ndarray) -> None:
        """The contact check of the ``leapfrog`` integrator for hull ``i``: the hull's
        footprint polygon ``footprint`` (k, 2) (m, body frame, convex, counter-clockwise; the
        same for every hull) and its obstacle rectangles ``rects`` (R_i, 9)
        (:func:`obstacles_touched`); with ``stop_on_contact`` a hull stops after the step at
        whose start it touched one (as MuJoCo's contacts stop a ``mujoco`` hull)."""
        fp = np.ascontiguousarray(footprint, dtype=np.float64)
        r = np.asarray(rects, dtype=np.float64).reshape(-1, 9)
        if self.footprint.shape != fp.shape or not np.array_equal(self.footprint, fp):
            self.footprint = fp
            self._args = None
        if r.shape[0] > self.obstacles.shape[1]:  # room for more rectangles
            grown = np.zeros((self.n, r.shape[0], 9))
            grown[:, : self.obstacles.shape[1]] = self.obstacles
            self.obstacles = grown
            self._args = None
        self.obstacles[i, : r.shape[0]] = r
        self.n_obstacles[i] = r.shape[0]
        self.touching[i] = 0

    def contact_counts(self) -> np.ndarray:
        """Each hull's contact count now, (N,) int64: MuJoCo's (``mujoco``: one compiled read
        of the ``mjData`` fields, not N attribute reads), or the obstacles a ``leapfrog`` hull
        touched at its last step's start (zeros without obstacles)."""
        if not self.datas:
            return self.touching.copy()
        out = np.zeros(self.n, dtype=np.int64)
        if self.datas:
            args = (self.fields, out)
            if self._ncon_entry is None:
                self._ncon_entry = entry(ncon_rows, args)
            self._ncon_entry(*args)
        return out

    def body_velocities(self) -> np.ndarray:
        """Every hull's ``(u, v, p, r)`` (m/s, rad/s) at the whole step, (N, 4) (``p = 0`` for
        3 DOF): step 1 of :func:`run` (:func:`body_velocities`)."""
        args = (self.q, self.qv, self.qa, self.h, self.dofs == 4, self.linear_kin, self._nu)
        if self._nu_entry is None:
            self._nu_entry = entry(body_velocities, args)
        self._nu_entry(*args)
        return self._nu.copy()

    def body_velocity(self, i: int) -> tuple[float, float, float, float]:
        """Hull ``i``'s ``(u, v, p, r)`` as floats (:meth:`body_velocities`)."""
        u, v, p, r = self.body_velocities()[i].tolist()
        return u, v, p, r

    # ---- stepping --------------------------------------------------------------------------
    def advance(
        self, n: int, *, stop_on_contact: bool = False, mask: np.ndarray | None = None
    ) -> int:
        """``n`` physics steps of every hull; returns the fewest steps a hull took (fewer than
        ``n`` only where a contact stopped a hull, ``mujoco`` integrator: :attr:`stopped`
        holds each hull's untaken steps). ``mask``: step only the hulls where it is True.

        Raises:
            SimulationDiverged: a hull's state became non-finite or absurd (its state before
                that step is kept), or MuJoCo found a bad state and reset it (``mujoco``).
        """
        if type(n) is not int and (
            isinstance(n, bool) or not isinstance(n, int | np.integer)
        ):  # (an int first: the call of every control period)
            raise ValueError(
                f"the number of physics steps must be an int in [0, {MAX_STEPS}], got {n!r}"
            )
        if not 0 <= n <= MAX_STEPS:
            raise ValueError(
                f"the number of physics steps must be an int in [0, {MAX_STEPS}], got {n!r}"
            )
        if self._clock is not None:  # the hull's own mjData: MuJoCo's clock
            self.t[0] = self._clock.time
        return self._advance(self._integ, int(n), None, stop_on_contact, mask)

    def table_of_arrays(self) -> np.ndarray:
        """The int64 table of :func:`run`'s argument ``p``: the batch's shapes, then the
        addresses of its arrays (checked C-contiguous of the dtype the loop reads), which
        :attr:`_args` holds while the table is in use (built again when a window grows)."""
        f8, i8 = np.dtype(np.float64), np.dtype(np.int64)
        arrays = (
            (self.mps, i8), (self.dps, i8), (self.fields, i8), (self.inertia, f8),
            (self.kh, f8), (self.laws, i8), (self.table, f8), (self.kind_index, i8),
            (self.chan, f8), (self.kw, f8), (self.q, f8), (self.qv, f8), (self.qa, f8),
            (self.qfrc, f8), (self.act, f8), (self.cmd, f8), (self.t, f8), (self.left, i8),
            (self.external, f8), (self.mode, i8), (self.const, f8), (self.inv_dt, f8),
            (self.k0, i8), *((w, f8) for w in self.windows), (self.drift_k, f8),
            (self.loads, f8), (self.forces, f8), (self.flags, f8), (self.hits, i8),
            (self.stopped, i8), (self.status, i8),
        )  # fmt: skip
        n, nq, nc = self.n, self.q.shape[1], self.act.shape[1]
        na, kt = self.table.shape[1:]
        shapes = {  # what _arrays reads each array as
            "mps": (n,), "dps": (n,), "fields": (n, 8), "inertia": (4,), "table": (n, na, kt),
            "kind_index": (na,), "chan": (nc, 9), "q": (n, nq), "qv": (n, nq), "qa": (n, nq),
            "qfrc": (n, nq), "act": (n, nc), "cmd": (n, nc), "forces": (n, na),
        }  # fmt: skip
        for name, want in shapes.items():
            if getattr(self, name).shape != want:
                raise ValueError(f"HullBatch.{name} has shape {getattr(self, name).shape}, "
                                 f"the loop reads {want}")  # fmt: skip
        for a, dt in arrays:
            if a.dtype != dt or not a.flags.c_contiguous:
                raise ValueError("the physics loop's arrays must be C-contiguous float64/int64")
        head = (
            n, nq, nc, na, kt, self.kh.size, self.laws.size, self.kw.size,
            *(w.shape[2] for w in self.windows), self.dofs, int(self.linear_kin),
            int(self.accel), self._mj_step,
        )  # fmt: skip
        p = self._p
        p[: len(head)] = head
        p[len(head) : len(head) + len(arrays)] = [a.ctypes.data for a, _ in arrays]
        p[len(head) + len(arrays)] = self._views
        # the obstacles of the leapfrog hulls' contact check (none in open water)
        contact = (self.footprint, self.obstacles, self.n_obstacles, self.touching)
        for a in contact:
            if a.dtype not in (f8, i8) or not a.flags.c_contiguous:
                raise ValueError("the physics loop's arrays must be C-contiguous float64/int64")
        if self.obstacles.shape[::2] != (n, 9) or self.footprint.shape[1:] != (2,):
            raise ValueError("HullBatch.obstacles must be (n, R, 9), footprint (k, 2)")
        p[49], p[50] = self.footprint.shape[0], self.obstacles.shape[1]
        p[51:55] = [a.ctypes.data for a in contact]
        self._args = (*(a for a, _ in arrays), *contact)
        return p

    def _advance(
        self,
        integ: int,
        n: int,
        only: int | None,
        stop_on_contact: bool = False,
        mask: np.ndarray | None = None,
    ) -> int:
        if only is None:
            self.left.fill(n)
            if mask is not None:
                self.left[~mask] = 0
        else:
            self.left.fill(0)
            self.left[only] = n
        self.stopped.fill(0)
        # the hulls that step: a reset's start (one hull) or a few masked ones stay serial
        busy = 1 if only is not None else self.n if mask is None else int(np.count_nonzero(mask))
        while True:
            if self._args is None:
                self.table_of_arrays()
            if self._entry is None:
                self._entry = self._entry_of(integ, stop_on_contact)
            args = (integ, bool(stop_on_contact), self.h, self._p)
            if busy >= PARALLEL_MIN and threads_ok() and not _DISABLED:
                use_threads()
                code = run_threads(address(run, ROWS_SIG), *args)
            else:
                code = self._entry(0, self.n, *args)
            if code == OK:
                return n - int(self.stopped.max()) if stop_on_contact else n
            codes = self.status[:, 0]
            if code == RESET:
                i = int(np.argmax(codes == RESET))
                raise SimulationDiverged(
                    f"simulation diverged by t = {self.t[i]:.3f} s (hull {i}): MuJoCo found a "
                    "NaN, infinite or huge value in the state or its acceleration and reset the "
                    "state; check the plant parameters, the timestep and the applied forces"
                )
            if code == DIVERGED:
                i = int(np.argmax(codes == DIVERGED))
                lo = self.loads[i].tolist()
                nu = lo[1:5] if self.dofs == 4 else (lo[1], lo[2], lo[4])
                diverged(lo[0], nu, lo[5:8])
            need = np.nonzero(codes == NEED)[0].tolist()
            slots = [int(self.status[i, 1]) for i in need]
            ks = [int(self.status[i, 2]) for i in need]
            grids = [self.processes[slot][i] for i, slot in zip(need, slots, strict=True)]
            for i, slot, (k0, rows) in zip(need, slots, load_windows(grids, ks), strict=True):
                self._install(i, slot, k0, rows)

    def _entry_of(self, integ: int, stop_on_contact: bool) -> Any:
        """:func:`run`'s compiled entry point (:func:`shipgym._jit.entry`); where compilation
        is off (``NUMBA_DISABLE_JIT``, the debugging path), the loop called on the arrays."""
        if not _DISABLED:
            return entry(run, (np.int64(0), np.int64(self.n), integ, stop_on_contact, self.h,
                               self._p))  # fmt: skip
        return lambda a, b, integ, stop, h, _p: _hulls(a, b, integ, stop, h, self._mj_step,
                                                       *self._args[:3], self._views, self.dofs,
                                                       self.linear_kin, self._args[3],
                                                       int(self.accel),
                                                       *self._args[4:])  # fmt: skip
