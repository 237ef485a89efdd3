"""Does a JAX backend of the batched physics pay? (issue 15: "JAX as an optional extra if it
pays (measure it)").

The Blue Lady's batched physics step of :class:`~shipgym.envs.batchphysics.BatchedPhysics`
(the default :class:`~shipgym.dynamics.model.PlantModel` in matrix form, the three propellers
with their advance-speed and tunnel losses and their rate-limited first-order lags, the
Blendermann (1994) wind load and the current, the leapfrog /
Euler update of the module docstring) written as one jitted ``jax.lax.scan`` over the ``k = 20``
physics steps of a control period, float64 (``jax_enable_x64``). The gusts and the current are
read as :class:`BatchedPhysics` reads them, once per control period, as ``(k, N)`` arrays
(:class:`~shipgym.disturbances._grid.GridBatch`, NumPy) and handed to the kernel.

What it prints:

1. parity: the JAX state against ``BatchedPhysics.step(20)`` (same start, commands and gust
   arrays, each run on its own) over 50 control periods (asserted <= 1e-9);
2. hull-steps per second of NumPy ``step(20)``, of the JAX kernel alone (state resident in
   JAX, inputs already there) and of the JAX step as the NumPy env would call it (gust lookup,
   state and inputs into JAX, kernel, state copied back to NumPy), interleaved (the order
   rotates every repeat), median [min, max] over the repeats, at N = 64, 256, 1024, 4096; the
   first call (trace + compile) separately; the transfer in / out per control period alone;
3. the whole env (``shipgym/BlueLadyTracking-v0`` as :class:`~shipgym.envs.vector.ShipVectorEnv`
   at N = 256): the share of ``env.step`` spent in the physics, and ``env.step`` with
   ``physics.step`` replaced by the JAX step, interleaved with the NumPy env (same seeds and
   actions, the trajectories compared).

jax is not a shipgym dependency: without it the script says so and exits 0. Run it in a venv
of its own, e.g. (from the repository root; ``.venv-jax`` is git-ignored like ``.venv``)::

    python -m venv .venv-jax && .venv-jax/bin/pip install -r requirements/lock.txt jax
    PYTHONPATH=. .venv-jax/bin/python benchmarks/bench_jax.py

XLA's CPU backend may use several threads; ``--threads 1`` pins it to one (NumPy's elementwise
ops are single-threaded), set before jax is imported.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from shipgym.dynamics import PlantModel
from shipgym.dynamics.actuators import Propeller
from shipgym.envs.batchphysics import BatchedPhysics

K = 20  # physics steps per control period (the open-water tasks: 1 s at h = 0.05 s)


def _import_jax(threads: int | None) -> Any:
    if threads is not None:
        flags = os.environ.get("XLA_FLAGS", "")
        os.environ["XLA_FLAGS"] = (
            f"{flags} --xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads={threads}"
        ).strip()
    try:
        import jax
    except ImportError:
        return None
    jax.config.update("jax_enable_x64", True)
    return jax


# ---- the JAX kernel ------------------------------------------------------------------------
def make_kernel(
    bp: BatchedPhysics, jax: Any, *, expand: bool = True, unroll: int = 1
) -> Callable[..., Any]:
    """``period(q, qv, qa, act, cmd, Vw, bw, vc, bc, gate) -> (q, qv, qa, act, ok)``: the
    ``k`` physics steps of :meth:`BatchedPhysics.step` as one jitted scan (``k`` the leading
    length of the ``(k, N)`` disturbance arrays; states ``(3, N)``, component-major as
    BatchedPhysics holds them; ``gate`` ``(N,)``: 1 for hulls with an aerodynamic load).

    Covers what the Blue Lady needs: a :class:`PlantModel`, fixed propellers, lagged channels.
    Inside, every state is three (N,) rows (``(3, N)`` only at the boundary). ``expand``: the
    3 x 3 matrix products as explicit sums of rows (elementwise, so that XLA fuses the whole
    step; zero entries skipped) instead of ``dot``; ``unroll``: the scan's ``unroll`` (> 1 is
    slower on CPU, and ``unroll=20`` did not finish compiling in 18 min here).
    """
    import jax.numpy as jnp
    from jax import lax

    from shipgym.disturbances.wind import _loads, _Ops

    p = bp.plant
    if not isinstance(p, PlantModel) or not all(type(a) is Propeller for a in bp.actuators):
        raise ValueError("the JAX kernel covers a PlantModel with fixed propellers only")
    if bp._any_servo or bp._any_integ:
        raise ValueError("the JAX kernel covers lagged actuator channels only")
    ops = _Ops(jnp.cos, jnp.sin, jnp.sqrt, jnp.arctan2)
    wk = bp._wind_load.args[1]  # the Blendermann constants of the batch (WindLoad._k)
    acts = bp.actuators
    ahead = [float(a.k_ahead) for a in acts]
    astern = [float(a.k_astern) for a in acts]
    quad = [a.law == "quadratic" for a in acts]
    # the advance-speed loss k_u (1 - w), the tunnel factor's d and 1/U_50, the rate limits
    kua = [float(a.advance * (1.0 - a.wake)) for a in acts]  # type: ignore[attr-defined]
    dep = [float(a.loss_depth) for a in acts]  # type: ignore[attr-defined]
    iu50 = [1.0 / a.loss_speed for a in acts]  # type: ignore[attr-defined]
    band, ramp = bp._rl_band[:, 0], bp._rl_step[:, 0]
    limited = [bool(np.isfinite(b)) for b in band]
    B = acts.configuration_matrix()
    A = np.asarray(p.M_A)
    a11, a22, a32 = A[0, 0], A[1, 1], A[2, 1]
    a23s = 0.5 * (A[1, 2] + A[2, 1])
    D = np.asarray(p.D_L)
    dq = [float(x) for x in p.d_quad]
    Mi = np.linalg.inv(p.mass_matrix())
    cor = p.coriolis
    m, xg = p.m, p.x_g
    mxg = m * xg
    h, hh = bp.h, 0.5 * bp.h
    alpha, lo, hi = bp._alpha, bp._lo, bp._hi

    def mv(M: np.ndarray, x: Any) -> tuple[Any, Any, Any]:
        """``M @ x`` for a constant (3, 3) ``M`` and three (N,) rows ``x``, as three rows."""
        if not expand:
            y = M @ jnp.stack(x)
            return y[0], y[1], y[2]
        rows = []
        for i in range(3):
            terms = [M[i, j] * x[j] for j in range(3) if M[i, j] != 0.0]
            acc = terms[0] if terms else jnp.zeros_like(x[0])
            for t in terms[1:]:
                acc = acc + t
            rows.append(acc)
        return rows[0], rows[1], rows[2]

    def qacc(q: Any, qv: Any, qa: Any, act: Any, Vw: Any, bw: Any, vc: Any, bc: Any,
             gate: Any) -> tuple[Any, Any, Any]:  # fmt: skip
        w0, w1, r = qv[0] + hh * qa[0], qv[1] + hh * qa[1], qv[2] + hh * qa[2]
        psi = q[2]
        c, s = jnp.cos(psi), jnp.sin(psi)
        u = c * w0 + s * w1
        v = c * w1 - s * w0
        d = bc - psi
        uc, vcb = vc * jnp.cos(d), vc * jnp.sin(d)
        ur, vr = u - uc, v - vcb
        # propellers (BatchedPhysics._actuator_kernel), then the wind load
        F = []
        for i, st in enumerate(act):
            kk = jnp.where(st >= 0.0, ahead[i], astern[i])
            f = (kk * jnp.abs(st) if quad[i] else kk) * st
            if kua[i]:
                f = f - kua[i] * jnp.abs(st) * ur
            if dep[i]:
                x = (ur * iu50[i]) ** 2
                f = f * (1.0 - dep[i] * x * jnp.exp(1.0 - x))
            F.append(f)
        X, Y, N = mv(B, F)
        wx, wy, wn = _loads(ops, wk, psi, u, v, Vw, bw)
        X, Y, N = X + wx * gate, Y + wy * gate, N + wn * gate
        # the plant in matrix form (BatchedPhysics._matrix_accel, current included)
        nr = (ur, vr, r)
        dl = mv(D, nr)
        f0, f1, f2 = (
            t - x - dq[i] * jnp.abs(z) * z if dq[i] else t - x
            for i, (t, x, z) in enumerate(zip((X, Y, N), dl, nr, strict=True))
        )
        if cor:
            w = a22 * vr + a23s * r
            a11u = a11 * ur
            f0 = f0 + (m * (xg * r + v) + w) * r
            f1 = f1 - (m * u + a11u) * r
            f2 = f2 - (mxg * r * u + w * ur - a11u * vr)
        f0 = f0 + a11 * (r * vcb)
        ay = r * uc
        f1 = f1 - a22 * ay
        f2 = f2 - a32 * ay
        ud, vd, rd = mv(Mi, (f0, f1, f2))
        bx = ud - r * v
        by = vd + r * u
        return c * bx - s * by, s * bx + c * by, rd

    def period(q: Any, qv: Any, qa: Any, act: Any, cmd: Any, Vw: Any, bw: Any, vc: Any,
               bc: Any, gate: Any) -> Any:  # fmt: skip
        rows = tuple(tuple(x[i] for i in range(3)) for x in (q, qv, qa, act))
        cm = tuple(cmd[i] for i in range(3))

        def fed(i: int, a: Any) -> Any:
            """The command the filter is fed (BatchedPhysics.step: the rate limit)."""
            if not limited[i]:
                return cm[i]
            gap = cm[i] - a
            eff = jnp.where(gap > band[i], jnp.minimum(a + ramp[i], cm[i]), cm[i])
            return jnp.where(-gap > band[i], jnp.maximum(a - ramp[i], cm[i]), eff)

        def body(carry: Any, x: Any) -> Any:
            q, qv, qa, act = carry
            qa = qacc(q, qv, qa, act, *x, gate)
            act = tuple(jnp.clip(a + alpha[i, 0] * (fed(i, a) - a), lo[i, 0], hi[i, 0])
                        for i, a in enumerate(act))  # lags (filterexact)  # fmt: skip
            qv = tuple(a + h * b for a, b in zip(qv, qa, strict=True))
            q = tuple(a + h * b for a, b in zip(q, qv, strict=True))
            return (q, qv, qa, act), None

        (q, qv, qa, act), _ = lax.scan(body, rows, (Vw, bw, vc, bc), unroll=unroll)
        q, qv, qa, act = (jnp.stack(x) for x in (q, qv, qa, act))
        ok = jnp.all(jnp.isfinite(qa)) & jnp.all(jnp.abs(qv) < 1e3)
        return q, qv, qa, act, ok

    return jax.jit(period)


def _times(bp: BatchedPhysics, k: int) -> np.ndarray:
    """Each hull's times of the ``k`` steps, by the clock's additions (BatchedPhysics.step)."""
    ts = np.empty((k, bp.n))
    ts[0] = bp.t
    for j in range(1, k):
        ts[j] = ts[j - 1] + bp.h
    return ts


def jax_step(bp: BatchedPhysics, kernel: Callable[..., Any], jax: Any) -> Callable[[int], None]:
    """A drop-in ``bp.step(k)`` that runs ``kernel``: the NumPy gust lookup, the state into
    JAX, the scan, the state copied back into ``bp`` (NumPy arrays, writable)."""
    gate = np.ones(bp.n)

    def step(k: int = 1) -> None:
        ts = _times(bp, k)
        Vw, bw, vc, bc = bp._disturbances(ts)
        g = gate if bp._aero_gate is None else bp._aero_gate
        if not bp.aerodynamics:
            g = np.zeros(bp.n)
        out = kernel(bp._q, bp._v, bp._a, bp._act, bp._cmd, Vw, bw, vc, bc, g)
        q, qv, qa, act, ok = jax.device_get(out)
        bp._q, bp._v, bp._a, bp._act = np.array(q), np.array(qv), np.array(qa), np.array(act)
        bp.t = ts[-1] + bp.h
        if not ok:
            raise RuntimeError("simulation diverged (JAX step)")

    return step


# ---- set-up --------------------------------------------------------------------------------
def make_batch(n: int, seed: int = 0) -> BatchedPhysics:
    """``n`` Blue Ladies, each with its own gusty wind and current, random start and commands."""
    rng = np.random.default_rng(seed)
    bp = BatchedPhysics("blue-lady", n, wind="3@300", current="0.05@90")
    for i in range(n):
        bp.set_disturbances(
            i, wind=(float(rng.uniform(0.5, 5.0)), float(rng.uniform(0, 360))),
            current=(float(rng.uniform(0.0, 0.1)), float(rng.uniform(0, 360))),
        )  # fmt: skip
    eta = rng.normal(0.0, [5.0, 5.0, 1.0], (n, 3))
    nu = rng.normal(0.0, [0.3, 0.1, 0.05], (n, 3))
    bp.reset(eta=eta, nu=nu, rngs=[np.random.default_rng(seed + 1 + i) for i in range(n)])
    bp.set_command(_commands(bp, rng))
    return bp


def _commands(bp: BatchedPhysics, rng: np.random.Generator) -> np.ndarray:
    return bp.actuators.action_to_command(rng.uniform(-1.1, 1.1, (bp.n, bp.actuators.n_channels)))


def _state(bp: BatchedPhysics) -> tuple[np.ndarray, ...]:
    return bp._q, bp._v, bp._a, bp._act


def parity(jax: Any, n: int = 64, periods: int = 50) -> dict[str, float]:
    """Max |JAX - NumPy| over ``periods`` control periods of their own runs from one start."""
    bp = make_batch(n)
    kernel = make_kernel(bp, jax)
    gate = np.ones(n)
    rng = np.random.default_rng(123)
    js = tuple(jax.numpy.asarray(a) for a in _state(bp))
    err = dict.fromkeys(("eta", "qvel", "qacc", "actuators_rel"), 0.0)
    span = (bp.upper - bp.lower)[:, None]
    for _ in range(periods):
        bp.set_command(_commands(bp, rng))
        Vw, bw, vc, bc = bp._disturbances(_times(bp, K))
        *js, ok = kernel(*js, bp._cmd, Vw, bw, vc, bc, gate)
        assert bool(ok)
        bp.step(K)
        q, qv, qa, act = (np.asarray(a) for a in js)
        err["eta"] = max(err["eta"], float(np.abs(q - bp._q).max()))
        err["qvel"] = max(err["qvel"], float(np.abs(qv - bp._v).max()))
        err["qacc"] = max(err["qacc"], float(np.abs(qa - bp._a).max()))
        err["actuators_rel"] = max(
            err["actuators_rel"], float((np.abs(act - bp._act) / span).max())
        )
    return err


# ---- timing --------------------------------------------------------------------------------
def interleaved(fns: dict[str, Callable[[], float]], repeats: int) -> dict[str, list[float]]:
    """Seconds of each timed function per repeat; the order rotates and alternates."""
    names = list(fns)
    out: dict[str, list[float]] = {k: [] for k in names}
    for r in range(repeats):
        order = names[r % len(names) :] + names[: r % len(names)]
        if r % 2:
            order = order[::-1]
        for k in order:
            out[k].append(fns[k]())
    return out


def _loop(fn: Callable[[], Any], reps: int, sync: Callable[[], Any] = lambda: None) -> Callable:
    def run() -> float:
        t0 = time.perf_counter()
        for _ in range(reps):
            fn()
        sync()
        return time.perf_counter() - t0

    return run


def _fmt(xs: list[float]) -> str:
    return f"{statistics.median(xs):10.3g} [{min(xs):.3g}, {max(xs):.3g}]"


def physics_row(jax: Any, n: int, repeats: int) -> dict[str, Any]:
    """One line of the physics table at ``n`` hulls (hull-steps per second and the parts)."""
    reps = max(5, int(4e5 / (n * K)))  # control periods per timing
    bp_np, bp_jx = make_batch(n), make_batch(n)
    kernel = make_kernel(bp_jx, jax)
    Vw, bw, vc, bc = bp_jx._disturbances(_times(bp_jx, K))
    host = (*_state(bp_jx), bp_jx._cmd, Vw, bw, vc, bc, np.ones(n))
    t0 = time.perf_counter()
    jax.block_until_ready(kernel(*host))
    jit_s = time.perf_counter() - t0
    dev = [jax.device_put(a) for a in host]
    box = {"s": dev[:4]}

    def resident() -> None:
        *box["s"], _ = kernel(*box["s"], *dev[4:])

    step = jax_step(bp_jx, kernel, jax)
    t = interleaved(
        {
            "numpy": _loop(lambda: bp_np.step(K), reps),
            "kernel": _loop(resident, reps, lambda: jax.block_until_ready(box["s"])),
            "env": _loop(lambda: step(K), reps),
        },
        repeats,
    )
    # the parts of the env call: the gust lookup (NumPy, in both backends); into JAX: the
    # kernel fed NumPy arrays (as the env call feeds it) less the kernel fed resident ones;
    # out of JAX: the four states fetched and copied into writable NumPy arrays
    ts = _times(bp_jx, K)
    lookup = _loop(lambda: bp_jx._disturbances(ts), 200)() / 200
    fed = _loop(lambda: jax.block_until_ready(kernel(*host)), 50)
    res = _loop(lambda: jax.block_until_ready(kernel(*dev)), 50)
    t_in = statistics.median(fed() - res() for _ in range(5)) / 50
    outs = kernel(*dev)
    t_out = _loop(lambda: [np.array(a) for a in jax.device_get(outs[:4])], 200)() / 200
    hs = {k: [n * K * reps / x for x in v] for k, v in t.items()}
    ratio = {
        k: statistics.median(a / b for a, b in zip(t["numpy"], t[k], strict=True))
        for k in ("kernel", "env")
    }
    row = {"n": n, "jit_s": jit_s, "lookup_us": lookup * 1e6, "in_us": t_in * 1e6,
           "out_us": t_out * 1e6, "hs": hs, "speedup": ratio}  # fmt: skip
    print(f"{n:5d} {_fmt(hs['numpy']):>30} {_fmt(hs['kernel']):>30} {_fmt(hs['env']):>30}"
          f" {jit_s:6.2f} {row['lookup_us']:10.0f} {row['in_us']:7.0f}"
          f" {row['out_us']:7.0f}")  # fmt: skip
    return row


def physics_table(jax: Any, sizes: list[int], repeats: int) -> list[dict[str, Any]]:
    print(f"\nhull-steps/s, median [min, max] over {repeats} interleaved repeats (k = {K});")
    print("jit s: first call (trace + compile); lookup / in / out: us per control period")
    print(f"{'N':>5} {'numpy step(20)':>30} {'jax kernel':>30} {'jax step (env call)':>30}"
          f" {'jit s':>6} {'lookup us':>10} {'in us':>7} {'out us':>7}")  # fmt: skip
    rows = [physics_row(jax, n, repeats) for n in sizes]
    print(f"\n{'N':>5} {'kernel / numpy':>15} {'env call / numpy':>17}   (speed-up, median)")
    for r in rows:
        print(f"{r['n']:5d} {r['speedup']['kernel']:15.2f} {r['speedup']['env']:17.2f}")
    return rows


def env_row(jax: Any, n: int, steps: int, repeats: int, kw: dict[str, Any]) -> None:
    """The vector env made with ``kw``: NumPy physics against the JAX step, interleaved."""
    from shipgym.envs.vector import tracking_vector_env

    label = ", ".join(f"{k}={v}" for k, v in kw.items()) or "defaults"
    envs = {b: tracking_vector_env(n, vessel="blue-lady", **kw) for b in ("numpy", "jax")}
    e_jx = envs["jax"]
    e_jx.physics.step = jax_step(e_jx.physics, make_kernel(e_jx.physics, jax), jax)  # type: ignore[method-assign]
    acts = np.random.default_rng(0).uniform(-1, 1, (steps, n, envs["numpy"].n_actions))
    share: list[float] = []

    def episode(b: str) -> float:
        e = envs[b]
        e.reset(seed=0)
        phys = {"s": 0.0}
        step0 = e.physics.step

        def timed(k: int = 1) -> None:
            t0 = time.perf_counter()
            step0(k)
            phys["s"] += time.perf_counter() - t0

        e.physics.step = timed  # type: ignore[method-assign]
        t0 = time.perf_counter()
        for a in acts:
            e.step(a)
        wall = time.perf_counter() - t0
        e.physics.step = step0  # type: ignore[method-assign]
        if b == "numpy":
            share.append(phys["s"] / wall)
        return wall

    episode("numpy"), episode("jax")  # untimed: the jit, warm caches
    diff = float(np.abs(envs["numpy"].physics._q - e_jx.physics._q).max())
    t = interleaved({"numpy": lambda: episode("numpy"), "jax": lambda: episode("jax")}, repeats)
    sp = [a / b for a, b in zip(t["numpy"], t["jax"], strict=True)]
    us = {b: [x / steps * 1e6 for x in v] for b, v in t.items()}
    hs = n * K / statistics.median(us["numpy"]) * 1e6
    print(f"  [{label}] env.step us: numpy {_fmt(us['numpy'])}, with the jax step "
          f"{_fmt(us['jax'])}")  # fmt: skip
    print(f"      env speed-up {_fmt(sp)}; physics share of the numpy env.step {_fmt(share)}")
    print(f"      numpy env {hs:,.0f} hull-steps/s; max |eta numpy - eta jax| after {steps} "
          f"steps {diff:.2e} m")  # fmt: skip


def env_table(jax: Any, n: int, steps: int, repeats: int) -> None:
    """The whole vector env: the physics share of env.step, and env.step with the JAX step."""
    print(f"\nshipgym/BlueLadyTracking-v0 as ShipVectorEnv, N = {n}, {steps} env steps per timing")
    for kw in ({}, {"observer": "kbf", "controller": "pid"}):
        env_row(jax, n, steps, repeats, kw)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[64, 256, 1024, 4096])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--threads", type=int, default=None, help="XLA CPU threads (default: XLA's)")
    ap.add_argument("--env-n", type=int, default=256)
    ap.add_argument("--env-steps", type=int, default=100)
    ap.add_argument("--no-env", action="store_true", help="skip the whole-env timings")
    args = ap.parse_args(argv)
    jax = _import_jax(args.threads)
    if jax is None:
        print(
            "bench_jax: SKIPPED: jax is not installed (it is not a shipgym dependency); "
            "install jax (CPU: pip install jax) in a separate venv to run this benchmark"
        )
        return 0
    print(
        f"jax {jax.__version__} on {jax.devices()}, numpy {np.__version__}, "
        f"x64 {jax.config.jax_enable_x64}, XLA_FLAGS={os.environ.get('XLA_FLAGS', '')!r}"
    )
    err = parity(jax)
    print(
        "parity over 50 control periods (N = 64), max |jax - numpy|: "
        + ", ".join(f"{k} {v:.2e}" for k, v in err.items())
    )
    assert max(err.values()) <= 1e-9, err
    physics_table(jax, args.sizes, args.repeats)
    if not args.no_env:
        env_table(jax, args.env_n, args.env_steps, args.repeats)
    return 0


if __name__ == "__main__":
    sys.exit(main())
