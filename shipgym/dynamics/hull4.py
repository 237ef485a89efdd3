r"""A 4-DOF (surge, sway, roll, yaw) hull: ``M nu_dot + D(nu_r) nu_r + g(eta) = tau``.

Kinematics ``x_dot = u cos(psi) - v cos(phi) sin(psi)``, ..., ``psi_dot = r cos(phi)``;
restoring ``g_K = K_phi phi``, ``K_phi = rho g nabla GM_T`` (Fossen 2011 ch. 7).

Public names: ``KINEMATICS``, ``Hull4``, ``is_hull4``, ``accel_linear4``.
Sources: Fossen (2011); Son & Nomoto (1982); Blanke & Christensen (1993); Van der Klugt (1987);
Radhakrishnan (n.d.); Christensen (1993).

Design notes: docs/design/dynamics.hull4.md.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shipgym._jit import njit

__all__ = ["KINEMATICS", "Hull4", "is_hull4", "accel_linear4"]

#: the kinematics a 4-DOF hull can use (module docstring)
KINEMATICS = ("fossen", "linear")

Mat4 = tuple[tuple[float, ...], ...]


def _mat4(name: str, a: ArrayLike) -> Mat4:
    arr = np.asarray(a, dtype=float)
    if arr.shape != (4, 4) or not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be a finite 4x4 matrix, got shape {arr.shape}")
    return tuple(tuple(float(x) for x in row) for row in arr)


@njit
def accel_linear4(k, u, v, p, r, phi, X, Y, K, N, u_c, v_c):  # type: ignore[no-untyped-def]
    r"""The ``linear4`` family's compiled acceleration (:data:`~shipgym._jit.ACCEL_SIG`).

    :meth:`Hull4.nu_dot` written out (the equations of the module docstring):
    ``M nu_dot = tau - (D_L + |u_r| D_u) nu_r - diag(d_quad) |nu_r| nu_r - g phi`` with
    ``g = [0, Y_phi, K_phi, N_phi]``, ``nu_r = [u - u_c, v - v_c, p, r]`` (Fossen 2011
    4-DOF form; Van der Klugt 1987, Blanke & Christensen 1993 linearised hulls). The
    ``|u_r| D_u`` terms are evaluated only where the flag ``k[55]`` is not 0.

    Args:
        k: the 56 constants of :meth:`Hull4.kernel_constants` (float64, C-contiguous).
        u, v, p, r: body velocity over ground (m/s, m/s, rad/s, rad/s).
        phi: roll angle (rad).
        X, Y, K, N: total external generalised force (N, N, N m, N m).
        u_c, v_c: body-frame current (m/s).

    Returns:
        ``(u_dot, v_dot, p_dot, r_dot)`` (m/s^2, m/s^2, rad/s^2, rad/s^2).
    """
    ur = u - u_c
    vr = v - v_c
    a = abs(ur)
    f1 = X - (k[16] * ur + k[17] * vr + k[18] * p + k[19] * r + k[48] * a * ur)
    f2 = Y - (k[20] * ur + k[21] * vr + k[22] * p + k[23] * r + k[49] * abs(vr) * vr)
    f2 -= k[53] * phi
    f3 = K - (k[24] * ur + k[25] * vr + k[26] * p + k[27] * r + k[50] * abs(p) * p)
    f3 -= k[52] * phi
    f4 = N - (k[28] * ur + k[29] * vr + k[30] * p + k[31] * r + k[51] * abs(r) * r)
    f4 -= k[54] * phi
    if k[55] != 0.0:
        f1 -= a * (k[32] * ur + k[33] * vr + k[34] * p + k[35] * r)
        f2 -= a * (k[36] * ur + k[37] * vr + k[38] * p + k[39] * r)
        f3 -= a * (k[40] * ur + k[41] * vr + k[42] * p + k[43] * r)
        f4 -= a * (k[44] * ur + k[45] * vr + k[46] * p + k[47] * r)
    return (
        k[0] * f1 + k[1] * f2 + k[2] * f3 + k[3] * f4,
        k[4] * f1 + k[5] * f2 + k[6] * f3 + k[7] * f4,
        k[8] * f1 + k[9] * f2 + k[10] * f3 + k[11] * f4,
        k[12] * f1 + k[13] * f2 + k[14] * f3 + k[15] * f4,
    )


@dataclass(frozen=True)
class Hull4:
    """A linear 4-DOF hull with quadratic damping and a roll restoring moment.

    Attributes:
        name: variant name.
        M: total inertia ``M_RB + M_A`` (kg, kg m, kg m^2), 4x4, order (u, v, p, r).
        D_L: linear damping, 4x4 (N s/m, N s, N m s).
        K_phi: roll restoring coefficient (N m/rad), > 0 for a stable hull.
        d_quad: quadratic damping magnitudes (4,), >= 0.
        m: rigid-body mass (kg), for the MuJoCo body.
        D_u: speed-proportional damping, 4x4 (N s^2/m^2, N s^2/m, N m s^2/m), multiplied by
            ``|u_r|``; zero by default.
        kinematics: ``"fossen"`` (default, the 4-DOF kinematics above) or ``"linear"``.
        phi_coupling: ``(Y_phi, N_phi)`` (N/rad, N m/rad): the sway force and yaw moment of
            the roll angle on the left-hand side (``g = [0, Y_phi, K_phi, N_phi] phi``).
        nabla: displaced volume (m^3), 0 when the model has none (a per-unit model); the wave
            moments of :mod:`shipgym.disturbances.rollwaves` need it.
        rho: water density (kg/m^3).

    The family's compiled kernel is :attr:`accel_kernel` (:func:`accel_linear4`) with the
    constant vector of :meth:`kernel_constants` (56 values, layout there).
    """

    #: the hull family (``[hull] family`` of a vessel package)
    family: ClassVar[str] = "linear4"
    #: the family's compiled acceleration, :func:`accel_linear4` (``ACCEL_SIG``)
    accel_kernel = staticmethod(accel_linear4)

    name: str
    M: Mat4
    D_L: Mat4
    K_phi: float
    d_quad: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    m: float = 0.0
    D_u: Mat4 = ((0.0,) * 4,) * 4
    kinematics: str = "fossen"
    phi_coupling: tuple[float, float] = (0.0, 0.0)
    nabla: float = 0.0
    rho: float = 1025.0
    dofs: int = field(default=4, init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "M", _mat4("M", self.M))
        object.__setattr__(self, "D_L", _mat4("D_L", self.D_L))
        object.__setattr__(self, "D_u", _mat4("D_u", self.D_u))
        if self.kinematics not in KINEMATICS:
            raise ValueError(
                f"kinematics must be one of {', '.join(KINEMATICS)}, got {self.kinematics!r}"
            )
        dq = tuple(float(x) for x in self.d_quad)
        if len(dq) != 4 or not all(np.isfinite(dq)) or min(dq) < 0:
            raise ValueError(f"d_quad must be four finite values >= 0, got {self.d_quad!r}")
        object.__setattr__(self, "d_quad", dq)
        pc = tuple(float(x) for x in self.phi_coupling)
        if len(pc) != 2 or not all(np.isfinite(pc)):
            raise ValueError(f"phi_coupling must be two finite values, got {self.phi_coupling!r}")
        object.__setattr__(self, "phi_coupling", pc)
        if not (np.isfinite(self.nabla) and self.nabla >= 0 and np.isfinite(self.rho)
                and self.rho > 0):  # fmt: skip
            raise ValueError(f"nabla must be >= 0 m^3 and rho > 0 kg/m^3, got {self.nabla!r}, "
                             f"{self.rho!r}")  # fmt: skip
        if not (np.isfinite(self.K_phi) and self.K_phi > 0):
            raise ValueError(f"K_phi must be > 0 (N m/rad), got {self.K_phi!r}")
        M = np.asarray(self.M)
        if not np.all(np.diag(M) > 0):
            raise ValueError(f"hull {self.name!r}: the diagonal of M must be > 0: {M}")
        if not np.linalg.cond(M) < 1e12:
            raise ValueError(f"hull {self.name!r}: M is singular: {M}")

    def mass_matrix(self) -> NDArray[np.float64]:
        """``M`` (4, 4)."""
        return np.array(self.M)

    def nu_dot(
        self,
        nu: ArrayLike,
        tau: ArrayLike,
        nu_c: ArrayLike | None = None,
        phi: ArrayLike = 0.0,
    ) -> NDArray[np.float64]:
        """Body acceleration (..., 4) by a linear solve (the matrix form).

        Args:
            nu: ``[u, v, p, r]`` (m/s, m/s, rad/s, rad/s), shape (..., 4).
            tau: ``[X, Y, K, N]`` (N, N, N m, N m), shape (..., 4).
            nu_c: current in the body frame ``[u_c, v_c]`` or ``[u_c, v_c, 0, 0]`` (m/s).
            phi: roll angle (rad).
        """
        nu = np.asarray(nu, dtype=float)
        tau = np.asarray(tau, dtype=float)
        nc = np.zeros(4)
        if nu_c is not None:
            c = np.asarray(nu_c, dtype=float)
            nc = np.concatenate([c[..., :2], np.zeros(c.shape[:-1] + (2,))], -1)
        nu_r = nu - nc
        D = np.asarray(self.D_L) + np.abs(nu_r[..., :1, None]) * np.asarray(self.D_u)
        quad = np.asarray(self.d_quad) * np.abs(nu_r) * nu_r
        damp = np.einsum("...ij,...j->...i", D, nu_r) + quad
        g = np.zeros(nu.shape)
        ph = np.asarray(phi, dtype=float)
        g[..., 1] = self.phi_coupling[0] * ph
        g[..., 2] = self.K_phi * ph
        g[..., 3] = self.phi_coupling[1] * ph
        rhs = tau - damp - g
        return np.linalg.solve(np.asarray(self.M), rhs[..., None])[..., 0]

    def kernel_constants(self) -> NDArray[np.float64]:
        """The constant vector ``k`` of :func:`accel_linear4` (a new float64, C-contiguous
        array of 56), order of the DOFs ``(u, v, p, r)``:

        - ``k[0:16]``: ``M^-1`` by rows (1/kg, 1/(kg m), 1/(kg m^2));
        - ``k[16:32]``: ``D_L`` by rows (N s/m, N s, N m s);
        - ``k[32:48]``: ``D_u`` by rows (N s^2/m^2, N s^2/m, N m s^2/m);
        - ``k[48:52]``: ``d_quad`` (N s^2/m^2, N s^2/m^2, N m s^2, N m s^2);
        - ``k[52:55]``: ``K_phi`` (N m/rad), ``Y_phi`` (N/rad), ``N_phi`` (N m/rad);
        - ``k[55]``: 1.0 where ``D_u`` has a non-zero entry, else 0.0 (its terms skipped).
        """
        E = np.asarray(self.D_u, dtype=np.float64)
        return np.ascontiguousarray(
            np.concatenate([
                np.linalg.inv(np.asarray(self.M, dtype=np.float64)).ravel(),
                np.asarray(self.D_L, dtype=np.float64).ravel(),
                E.ravel(),
                self.d_quad,
                (self.K_phi, *self.phi_coupling, 1.0 if np.any(E != 0.0) else 0.0),
            ]),
            dtype=np.float64,
        )  # fmt: skip


def is_hull4(plant: Any) -> bool:
    """Whether ``plant`` is a 4-DOF hull model: ``dofs == 4`` and a batched ``nu_dot(nu, tau,
    nu_c, phi)`` (a :class:`Hull4`, a :class:`~shipgym.dynamics.blanke4.Blanke4Hull`, ...)."""
    return getattr(plant, "dofs", None) == 4 and callable(getattr(plant, "nu_dot", None))
