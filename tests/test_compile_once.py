"""One compiled signature per law, whatever path reaches it: a read-only array (or a literal
argument) is a Numba type of its own, and each type is a whole compile of the law (the
azimuth allocation takes about 15 s to compile here). The public paths below reach each law
serially, in ranges of rows on threads and with read-only inputs; every signature the law
has must be free of read-only arrays and literals: each path passes the one type."""

from __future__ import annotations

import math

import numpy as np
from numba import types

from shipgym.controllers.allocation import WLSAllocator, azimuth, wls
from shipgym.controllers.allocation.azimuth import AzimuthAllocator, Azimuths, allocate_azimuth
from shipgym.controllers.allocation.wls import allocate_wls
from shipgym.disturbances import spectra
from shipgym.disturbances.spectra import harmonic_sums
from shipgym.observers import wavefilter
from shipgym.observers.wavefilter import DiscreteKF


def _frozen(a):
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


def _odd_types(dispatcher):
    """The signatures of ``dispatcher`` with a literal or a read-only array among their
    arguments."""
    return [
        sig
        for sig in dispatcher.signatures
        if any(
            isinstance(t, types.Literal) or (isinstance(t, types.Array) and not t.mutable)
            for t in sig
        )
    ]


def test_allocation_laws_compile_once_for_serial_and_threaded_calls_and_frozen_inputs():
    az = Azimuths(
        positions=_frozen([[-30.0, 5.0], [-30.0, -5.0], [25.0, 0.0]]),
        f_max=_frozen([2e5, 2e5, 1e5]),
        angle_prev=_frozen([0.1, -0.1, 1.5]),
        max_dangle=0.2,
        reversible=True,
    )
    tau = _frozen([1e5, 5e4, 1e6])
    allocate_azimuth(tau, az)  # one request, the Azimuths' read-only angles
    al = AzimuthAllocator(az)
    rng = np.random.default_rng(0)
    for n in (3, azimuth.PARALLEL_MIN + 4):  # the serial law, then the threaded one
        taus = _frozen(rng.normal(0.0, [1e5, 1e5, 1e6], (n, 3)))
        al.batch(taus, _frozen(np.tile(az.angle_prev, (n, 1))))
    B = _frozen([[1.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 1.0], [5.0, -5.0, 20.0, -20.0]])
    lo, hi = _frozen([-1e4] * 4), _frozen([1e4] * 4)
    allocate_wls(_frozen([1e3, 2e3, 1e4]), B, lo, hi)
    wa = WLSAllocator(B, lo, hi)
    for n in (2, wls.PARALLEL_MIN + 3):
        wa.batch(_frozen(rng.normal(0.0, [1e3, 1e3, 1e4], (n, 3))))
    for law in (azimuth.azimuth_law, wls.wls_law):
        assert len(law.signatures) == 1, law.signatures
        assert not _odd_types(law), (law, _odd_types(law))


def test_filter_update_and_harmonic_sums_compile_once_for_frozen_inputs():
    n = 2
    kf = DiscreteKF(np.eye(n), np.eye(n), np.eye(n), np.eye(n), np.eye(n), np.eye(n), 1.0)
    kf.step(_frozen(np.zeros(n)), np.zeros(n))  # one env's row: a broadcast, read-only view
    kf3 = DiscreteKF(np.eye(n), np.eye(n), np.eye(n), np.eye(n), np.eye(n), np.eye(n), 1.0,
                     envs=3)  # fmt: skip
    kf3.step(_frozen(np.zeros((3, n))), np.zeros((3, n)))
    w, eps = _frozen([0.5, 1.0]), _frozen([0.0, math.pi / 3])
    harmonic_sums(0.0, 0.1, 50, w, eps, _frozen([[1.0, 2.0]]), real=True)
    harmonic_sums(0.0, 0.1, 50, w, eps, np.array([[1.0, 2.0]]), real=True)
    for law in (wavefilter._kf_update, spectra.harmonic_rows):
        assert law.signatures, law
        assert not _odd_types(law), (law, _odd_types(law))
