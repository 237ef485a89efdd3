r"""The 3-DOF manoeuvring model (Fossen 2011, ch. 6-7; Tomera 2014 eqs. 3-7).

Public names: ``PlantModel``, ``plant_model``, ``PLANT_VARIANTS``, ``seed_linear_matrices``,
``accel_fossen3``.

Design notes: docs/design/dynamics.model.md.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._jit import njit
from shipgym._text import did_you_mean

from .params import HullParameters

__all__ = [
    "PlantModel",
    "plant_model",
    "PLANT_VARIANTS",
    "seed_linear_matrices",
    "accel_fossen3",
]

Mat3 = tuple[tuple[float, float, float], tuple[float, float, float], tuple[float, float, float]]


def _mat(a: ArrayLike) -> Mat3:
    arr = np.asarray(a, dtype=float)
    if arr.shape != (3, 3) or not np.all(np.isfinite(arr)):
        raise ValueError(f"expected a finite 3x3 matrix, got shape {arr.shape}: {arr!r}")
    return tuple(tuple(float(x) for x in row) for row in arr)  # type: ignore[return-value]


@njit
def accel_fossen3(k, u, v, p, r, phi, X, Y, K, N, u_c, v_c):  # type: ignore[no-untyped-def]
    r"""The ``fossen3`` family's compiled acceleration (:data:`~shipgym._jit.ACCEL_SIG`).

    :meth:`PlantModel.nu_dot` (Fossen 2011 ch. 6-7, Tomera 2014 eqs. 3-7) written out component
    by component:
    ``M nu_dot = tau - C_RB(nu) nu - C_A(nu_r) nu_r - D(nu_r) nu_r + M_A nu_c_dot``.

    Args:
        k: the 30 constants of :meth:`PlantModel.kernel_constants` (float64, C-contiguous).
        u, v, p, r: body velocity over ground (m/s, m/s, rad/s, rad/s); ``p`` is ignored.
        phi: roll angle (rad), ignored (3 DOF).
        X, Y, K, N: total external generalised force (N, N, N m, N m); ``K`` is ignored.
        u_c, v_c: body-frame current (m/s), constant in NED.

    Returns:
        ``(u_dot, v_dot, 0.0, r_dot)`` (m/s^2, m/s^2, rad/s^2, rad/s^2).
    """
    a11 = k[0]
    a22 = k[1]
    a32 = k[2]
    d11 = k[3]
    d12 = k[4]
    d13 = k[5]
    d21 = k[6]
    d22 = k[7]
    d23 = k[8]
    d31 = k[9]
    d32 = k[10]
    d33 = k[11]
    q1 = k[12]
    q2 = k[13]
    q3 = k[14]
    m = k[24]
    mxg = k[25]
    xg = k[26]
    a22c = k[27]
    a23c = k[28]
    a11c = k[29]
    ur = u - u_c
    vr = v - v_c
    # damping D(nu_r) nu_r
    fx = X - (d11 * ur + d12 * vr + d13 * r + q1 * abs(ur) * ur)
    fy = Y - (d21 * ur + d22 * vr + d23 * r + q2 * abs(vr) * vr)
    fn = N - (d31 * ur + d32 * vr + d33 * r + q3 * abs(r) * r)
    # Coriolis-centripetal C_RB(nu) nu + C_A(nu_r) nu_r
    w = a22c * vr + a23c * r
    a11u = a11c * ur
    fx += m * (xg * r + v) * r + w * r
    fy -= m * u * r + a11u * r
    fn -= mxg * r * u + w * ur - a11u * vr
    # + M_A nu_c_dot, nu_c_dot = [r v_c, -r u_c, 0]
    ay = -r * u_c
    fx += a11 * (r * v_c)
    fy += a22 * ay
    fn += a32 * ay
    return (
        k[15] * fx + k[16] * fy + k[17] * fn,
        k[18] * fx + k[19] * fy + k[20] * fn,
        0.0,
        k[21] * fx + k[22] * fy + k[23] * fn,
    )


@dataclass(frozen=True)
class PlantModel:
    """A 3-DOF hull model: inertia, Coriolis-centripetal and damping terms.

    Attributes:
        name: variant name.
        M_RB: rigid-body inertia (kg, kg m, kg m^2), 3x3.
        M_A: added mass (kg, kg m, kg m^2), 3x3,
            ``-[[X_udot,0,0],[0,Y_vdot,Y_rdot],[0,N_vdot,N_rdot]]``.
        D_L: linear damping (N s/m, N s, N m s), 3x3.
        d_quad: quadratic damping magnitudes ``(-X_uu, -Y_vv, -N_rr)`` (N s^2/m^2, N s^2/m^2,
            N m s^2), all >= 0.
        coriolis: include C_RB(nu) and C_A(nu_r) (Fossen 2011 eqs. 6.43, 6.54).
        m, x_g: rigid-body mass (kg) and longitudinal CG (m), used by C_RB.

    The family's compiled kernel is :attr:`accel_kernel` (:func:`accel_fossen3`) with the
    constant vector of :meth:`kernel_constants` (30 values, layout there).
    """

    #: the hull family (``[hull] family`` of a vessel package)
    family: ClassVar[str] = "fossen3"
    dofs: ClassVar[int] = 3
    #: the family's compiled acceleration, :func:`accel_fossen3` (``ACCEL_SIG``)
    accel_kernel = staticmethod(accel_fossen3)

    name: str
    M_RB: Mat3
    M_A: Mat3
    D_L: Mat3
    d_quad: tuple[float, float, float] = (0.0, 0.0, 0.0)
    coriolis: bool = True
    m: float = 0.0
    x_g: float = 0.0
    _k: Any = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        for nm in ("M_RB", "M_A", "D_L"):
            object.__setattr__(self, nm, _mat(getattr(self, nm)))
        dq = tuple(float(x) for x in self.d_quad)
        if len(dq) != 3 or not all(np.isfinite(dq)) or min(dq) < 0:
            raise ValueError(f"d_quad must be three finite values >= 0, got {self.d_quad!r}")
        object.__setattr__(self, "d_quad", dq)
        M = np.add(self.M_RB, self.M_A)
        if not np.all(np.diag(M) > 0):
            raise ValueError(
                f"plant {self.name!r}: the diagonal of M = M_RB + M_A must be > 0: {M}"
            )
        if not np.linalg.cond(M) < 1e12:
            raise ValueError(f"plant {self.name!r}: M = M_RB + M_A is singular: {M}")
        if self.coriolis and not self.m > 0:
            raise ValueError(f"plant {self.name!r}: m must be > 0 when coriolis=True")
        object.__setattr__(self, "_k", _constants(self, np.linalg.inv(M)))

    # ---- matrix form (batched) -------------------------------------------------------------
    def mass_matrix(self) -> NDArray[np.float64]:
        """``M = M_RB + M_A`` (3, 3)."""
        return np.add(self.M_RB, self.M_A)

    def coriolis_rb(self, nu: ArrayLike) -> NDArray[np.float64]:
        """``C_RB(nu)`` (..., 3, 3), Fossen 2011 eq. 6.43 (planar, x_g on the centre line)."""
        nu = np.asarray(nu, dtype=float)
        out = np.zeros(nu.shape[:-1] + (3, 3))
        if self.coriolis:
            u, v, r = nu[..., 0], nu[..., 1], nu[..., 2]
            out[..., 0, 2] = -self.m * (self.x_g * r + v)
            out[..., 1, 2] = self.m * u
            out[..., 2, 0] = self.m * (self.x_g * r + v)
            out[..., 2, 1] = -self.m * u
        return out

    def coriolis_a(self, nu_r: ArrayLike) -> NDArray[np.float64]:
        """``C_A(nu_r)`` (..., 3, 3), Fossen 2011 eq. 6.54 with the symmetric part of M_A."""
        nu_r = np.asarray(nu_r, dtype=float)
        out = np.zeros(nu_r.shape[:-1] + (3, 3))
        if self.coriolis:
            A = np.asarray(self.M_A)
            a23 = 0.5 * (A[1, 2] + A[2, 1])
            u, v, r = nu_r[..., 0], nu_r[..., 1], nu_r[..., 2]
            out[..., 0, 2] = -(A[1, 1] * v + a23 * r)
            out[..., 1, 2] = A[0, 0] * u
            out[..., 2, 0] = A[1, 1] * v + a23 * r
            out[..., 2, 1] = -A[0, 0] * u
        return out

    def damping(self, nu_r: ArrayLike) -> NDArray[np.float64]:
        """``D(nu_r) = D_L + diag(d_quad * |nu_r|)`` (..., 3, 3)."""
        nu_r = np.asarray(nu_r, dtype=float)
        out = np.broadcast_to(np.asarray(self.D_L), nu_r.shape[:-1] + (3, 3)).copy()
        idx = np.arange(3)
        out[..., idx, idx] += np.asarray(self.d_quad) * np.abs(nu_r)
        return out

    def nu_dot(
        self, nu: ArrayLike, tau: ArrayLike, nu_c: ArrayLike | None = None
    ) -> NDArray[np.float64]:
        """Body-frame acceleration (..., 3) from the matrix form, by a linear solve.

        Args:
            nu: body velocity ``[u, v, r]`` (m/s, m/s, rad/s), shape (..., 3).
            tau: total external generalised force ``[X, Y, N]`` (N, N, N m), shape (..., 3).
            nu_c: body-frame current velocity ``[u_c, v_c, 0]`` (m/s), constant in NED.
        """
        nu = np.asarray(nu, dtype=float)
        tau = np.asarray(tau, dtype=float)
        nu_c = np.zeros(3) if nu_c is None else np.asarray(nu_c, dtype=float)
        nu_r = nu - nu_c
        r = nu[..., 2]
        nu_c_dot = np.stack([r * nu_c[..., 1], -r * nu_c[..., 0], np.zeros_like(r)], axis=-1)
        mv = lambda A, x: np.einsum("...ij,...j->...i", A, x)  # noqa: E731
        rhs = (
            tau
            - mv(self.coriolis_rb(nu), nu)
            - mv(self.coriolis_a(nu_r), nu_r)
            - mv(self.damping(nu_r), nu_r)
            + mv(np.asarray(self.M_A), nu_c_dot)
        )
        M = self.mass_matrix()
        return np.linalg.solve(M, rhs[..., None])[..., 0]

    # ---- the compiled law's constants ----------------------------------------------------
    def kernel_constants(self) -> NDArray[np.float64]:
        """The constant vector ``k`` of :func:`accel_fossen3` (a new float64, C-contiguous
        array of 30):

        - ``k[0:3]``: ``a11, a22, a32`` of ``M_A`` (kg, kg, kg m) for ``M_A nu_c_dot``;
        - ``k[3:12]``: ``D_L`` by rows (N s/m, N s, N m s);
        - ``k[12:15]``: ``d_quad`` (N s^2/m^2, N s^2/m^2, N m s^2);
        - ``k[15:24]``: ``M^-1`` by rows (1/kg, 1/(kg m), 1/(kg m^2));
        - ``k[24:30]``: the Coriolis coefficients ``m`` (kg), ``m x_g`` (kg m), ``x_g`` (m),
          ``a22`` (kg), ``(a23 + a32)/2`` (kg m, the symmetric part), ``a11`` (kg), each times
          the Coriolis switch (0 when ``coriolis=False``).
        """
        return np.array(self._k, dtype=np.float64)

    def with_(self, **changes: Any) -> PlantModel:
        """A copy with some fields changed (frozen-dataclass ``replace``)."""
        return replace(self, **changes)


def _constants(p: PlantModel, Mi: NDArray[np.float64]) -> tuple[float, ...]:
    A = p.M_A
    a11, a22, a32 = A[0][0], A[1][1], A[2][1]
    a23s = 0.5 * (A[1][2] + A[2][1])
    # the Coriolis coefficients (zero when the terms are off: products with a switch of 1 left
    # out, so that the usual case costs nothing)
    cor = 1.0 if p.coriolis else 0.0
    m = p.m * cor
    rows = [float(x) for row in p.D_L for x in row]
    inv = [float(x) for row in Mi for x in row]
    return tuple(float(x) for x in (a11, a22, a32, *rows, *p.d_quad, *inv, m, m * p.x_g,
                                    p.x_g, a22 * cor, a23s * cor, a11 * cor))  # fmt: skip


def seed_linear_matrices() -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The Blue Lady's ``(M, D_L)`` exactly as printed in Tomera (2014) eqs. 49-50.

    The design model of the paper's controllers and EKF for that vessel (equal to
    ``load_vessel("blue-lady").design``); no function below the registry defaults to it.
    """
    M = np.diag([23664.9, 24830.6, 455182.1])
    D_L = np.array([[21.10, 0.0, 0.0], [0.0, 259.8, -855.4], [0.0, -855.4, 6130.5]])
    return M, D_L


def _from_hull(
    hull: HullParameters,
    name: str,
    *,
    coriolis: bool = True,
    quadratic_damping: bool = True,
    sway_yaw_coupling: bool = True,
) -> PlantModel:
    h = hull
    M_RB = [[h.m, 0, 0], [0, h.m, h.m * h.x_g], [0, h.m * h.x_g, h.I_z]]
    c = 1.0 if sway_yaw_coupling else 0.0
    M_A = [[-h.X_udot, 0, 0], [0, -h.Y_vdot, -c * h.Y_rdot], [0, -c * h.N_vdot, -h.N_rdot]]
    D_L = [[-h.X_u, 0, 0], [0, -h.Y_v, -h.Y_r], [0, -h.N_v, -h.N_r]]  # Tomera (2014) eq. 7
    dq = (-h.X_uu, -h.Y_vv, -h.N_rr) if quadratic_damping else (0.0, 0.0, 0.0)
    return PlantModel(name, M_RB, M_A, D_L, dq, coriolis, h.m, h.x_g)


def _default(hull: HullParameters) -> PlantModel:
    """The richer plant: Table 2 M and D_L, Coriolis, quadratic damping, sway-yaw coupling."""
    return _from_hull(hull, "default")


def _seed_linear(hull: HullParameters) -> PlantModel:
    """The Blue Lady's ``M nu_dot + D_L nu = tau`` of Tomera (2014) eqs. 49-50, nothing else."""
    M, D_L = seed_linear_matrices()
    M_RB = np.diag([hull.m, hull.m, M[2, 2]])
    return PlantModel("seed-linear", M_RB, M - M_RB, D_L, (0.0, 0.0, 0.0), False, hull.m, 0.0)


PLANT_VARIANTS: dict[str, Callable[..., PlantModel]] = {
    "default": _default,
    "seed-linear": _seed_linear,
}


def plant_model(
    name: str = "default", hull: HullParameters | None = None, **options: bool
) -> PlantModel:
    """A plant variant by name.

    Args:
        name: ``"default"`` (richer plant) or ``"seed-linear"`` (Tomera 2014 eqs. 49-50 only);
            a vessel package's further variants (the Blue Lady's ``"table2-literal"``) come
            from :meth:`~shipgym.dynamics.vessel.Vessel.plant`.
        hull: hull parameters, required (e.g. ``load_vessel("blue-lady").hull`` or
            :data:`~shipgym.dynamics.params.BLUE_LADY_HULL`); ``"seed-linear"`` is the Blue
            Lady's model of Tomera (2014) and takes only the mass ``m`` from it.
        **options: for ``"default"`` only: ``coriolis``, ``quadratic_damping``,
            ``sway_yaw_coupling`` (bools) to switch the richer terms off one by one.

    Raises:
        TypeError: no ``hull`` given.
        ValueError: unknown name or option.
    """
    if hull is None:
        raise TypeError(
            "plant_model() needs the hull: pass hull=..., e.g. load_vessel('blue-lady').hull "
            "(or use Vessel.plant(name))"
        )
    if name not in PLANT_VARIANTS:
        raise ValueError(
            f"unknown plant variant {name!r}{did_you_mean(name, PLANT_VARIANTS)}; choose one "
            f"of: {', '.join(PLANT_VARIANTS)}"
        )
    if name == "default":
        valid = {"coriolis", "quadratic_damping", "sway_yaw_coupling"}
        bad = sorted(set(options) - valid)
        if bad:
            raise ValueError(f"unknown plant option(s) {bad}; valid: {sorted(valid)}")
        return _from_hull(hull, "default", **options)
    if options:
        raise ValueError(f"plant {name!r} takes no options, got {sorted(options)}")
    return PLANT_VARIANTS[name](hull)
