"""Command chatter statistics (shipgym.metrics.command_chatter) on synthetic signals."""

import math

import numpy as np
import pytest

from shipgym.metrics import CHATTER_KEYS, ManoeuvreMetrics, command_chatter


def _two_tones(a_slow: float, a_fast: float, p_slow: float, p_fast: float, k: int, dt: float):
    t = dt * np.arange(k)
    return a_slow * np.cos(2 * np.pi * t / p_slow) + a_fast * np.cos(2 * np.pi * t / p_fast)


@pytest.mark.parametrize(
    ("a_slow", "a_fast", "p_slow", "p_fast"),
    [(1.0, 0.5, 50.0, 10.0), (0.2, 0.6, 40.0, 8.0), (0.5, 0.0, 100.0, 5.0)],
)
def test_hf_fraction_of_two_tones_is_their_power_split(a_slow, a_fast, p_slow, p_fast):
    # a tone of amplitude A carries variance A^2 / 2: the share below 20 s is the fast one's
    x = _two_tones(a_slow, a_fast, p_slow, p_fast, 2000, 1.0)
    expected = a_fast**2 / (a_slow**2 + a_fast**2)
    hf = command_chatter(x, 1.0)["hf_variance_fraction"][0]
    # linear detrending removes a little of each tone (an integer number of cycles of a cosine
    # is not orthogonal to t); the leak is below 1e-3 at 2000 samples
    assert hf == pytest.approx(expected, abs=2e-3)


def test_hf_fraction_ignores_a_linear_trend_and_counts_periods_below_20_s():
    dt = 0.5
    t = dt * np.arange(4000)
    slow = np.cos(2 * np.pi * t / 25.0)  # 25 s: low frequency
    fast = 0.5 * np.cos(2 * np.pi * t / 15.0)  # 15 s: high frequency
    trend = 0.3 + 1e-4 * t
    hf = command_chatter(slow + fast + trend, dt)["hf_variance_fraction"][0]
    assert hf == pytest.approx(0.25 / 1.25, abs=2e-3)
    # not resolved above 1/hf_period at this period: NaN, not a number that means nothing
    assert math.isnan(command_chatter(slow, 15.0)["hf_variance_fraction"][0])
    # no variance: no high-frequency content
    assert command_chatter(np.full(50, 0.3), 1.0)["hf_variance_fraction"] == [0.0]


def test_white_noise_hf_fraction_is_the_band_share():
    # white noise spreads its variance evenly over 0..1/(2 dt): at dt = 1 s the share of
    # periods below 20 s is (0.5 - 0.05) / 0.5 = 0.9
    x = np.random.default_rng(1).normal(size=20000)
    assert command_chatter(x, 1.0)["hf_variance_fraction"][0] == pytest.approx(0.9, abs=0.01)


def test_reversals_count_sign_changes_only_when_the_band_is_left():
    dt = 1.0
    # dithering inside +-0.02 is not a reversal; leaving it on the other side is
    x = [0.5, 0.01, -0.015, 0.02, 0.4, -0.03, -0.5, 0.0, 0.3, 0.0, 0.0, 0.0]
    out = command_chatter(np.array(x), dt)
    # +1 (0.5) -> -1 (-0.03): one; -1 -> +1 (0.3): two; 12 samples = 0.2 min
    assert out["reversals_per_min"][0] == pytest.approx(2 / 0.2)
    # the band as an argument
    assert command_chatter(np.array(x), dt, band=0.04)["reversals_per_min"][0] == pytest.approx(
        2 / 0.2
    )
    assert command_chatter(np.array(x), dt, band=0.35)["reversals_per_min"][0] == pytest.approx(
        1 / 0.2
    )
    # a square wave of period 4 s reverses every 2 s: 119 reversals in 240 s (4 min)
    sq = np.tile([1.0, 1.0, -1.0, -1.0], 60)
    assert command_chatter(sq, 1.0)["reversals_per_min"][0] == pytest.approx(119 / 4)


def test_limit_fraction_travel_and_non_reversible_channels():
    c = np.array([[1.0, 0.0], [1.0, 0.5], [-1.0, -0.5], [0.5, 0.5]])
    out = command_chatter(c, 15.0, reversible=[True, False])  # 4 x 15 s = 1 min
    assert out["limit_fraction"] == pytest.approx([0.75, 0.0])
    assert out["travel_per_min"] == pytest.approx([0.0 + 2.0 + 1.5, 0.5 + 1.0 + 1.0])
    assert out["reversals_per_min"][0] == pytest.approx(2.0)
    assert out["reversals_per_min"][1] == 0.0  # it cannot reverse


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="finite"):
        command_chatter([0.0, float("nan")], 1.0)
    with pytest.raises(ValueError, match="dt"):
        command_chatter([0.0, 1.0], 0.0)
    with pytest.raises(ValueError, match="band"):
        command_chatter([0.0, 1.0], 1.0, band=1.0)
    with pytest.raises(ValueError, match="reversible"):
        command_chatter(np.zeros((3, 2)), 1.0, reversible=[True])
    empty = command_chatter(np.zeros((0, 2)), 1.0)
    assert set(empty) == set(CHATTER_KEYS) and all(math.isnan(v) for v in empty["limit_fraction"])


def test_manoeuvre_metrics_records_commands():
    m = ManoeuvreMetrics(n_actuators=1, n_channels=2, control_period=1.0, reversible=[True, True])
    sq = np.tile([1.0, 1.0, -1.0, -1.0], 30)
    for k, v in enumerate(sq):
        m.record(float(k), np.zeros(3), np.zeros(3), command=[v, 0.5 * v])
    s = m.summary()
    assert s["reversals_per_min"] == pytest.approx([59 / 2] * 2)  # 120 s
    assert s["limit_fraction"] == pytest.approx([1.0, 0.0])
    with pytest.raises(ValueError, match="2 elements"):
        m.record(200.0, np.zeros(3), np.zeros(3), command=[1.0])
    assert all(math.isnan(v) for v in ManoeuvreMetrics().summary()["reversals_per_min"])


def test_chatter_table_gives_mean_and_worst_seed_per_channel():
    from shipgym.bench import chatter_table

    rows = [
        {"observer": "kbf", "chatter": {"reversals_per_min": [1.0, 3.0],
                                        "limit_fraction": [0.1, 0.0],
                                        "hf_variance_fraction": [0.2, 0.4],
                                        "travel_per_min": [2.0, 2.0]}},
        {"observer": "kbf", "chatter": {"reversals_per_min": [3.0, float("nan")],
                                        "limit_fraction": [0.3, 0.0],
                                        "hf_variance_fraction": [0.2, 0.2],
                                        "travel_per_min": [4.0, 2.0]}},
    ]  # fmt: skip
    line = chatter_table(rows).splitlines()[-1]
    assert line.startswith("| kbf | 2.00 [3.00] / 3.00 [3.00] | 20.0 [30.0] / 0.0 [0.0] |")
    assert "20.0 [20.0] / 30.0 [40.0]" in line and "3.00 [4.00] / 2.00 [2.00]" in line


@pytest.mark.parametrize("k", [4, 5, 50, 51, 1285])
@pytest.mark.parametrize("dt", [0.05, 1.0, 3.0])
def test_the_high_frequency_share_is_scipys_periodogram(k, dt):
    """The share computed with NumPy's FFT equals the one of SciPy's periodogram (rectangular
    window, linear detrend, density scaling) of each channel, the definition it implements."""
    from scipy.signal import periodogram

    rng = np.random.default_rng(k)
    a = rng.uniform(-1.0, 1.0, (k, 3))
    a[:, 1] = 0.2 + 0.3 * np.linspace(0.0, 1.0, k)  # a ramp: no variance left
    a[:, 2] += np.sin(0.7 * np.arange(k))
    got = command_chatter(a, dt)["hf_variance_fraction"]
    for j in range(3):
        f, p = periodogram(a[:, j], fs=1.0 / dt, window="boxcar", detrend="linear")
        total = float(p[1:].sum())
        want = float(p[f > 1.0 / 20.0].sum()) / total if total > 1e-24 else 0.0
        if 20.0 <= 2.0 * dt:
            assert math.isnan(got[j])
        else:
            assert got[j] == pytest.approx(want, abs=1e-12)


def test_the_compiled_sums_equal_a_plain_count_on_random_commands():
    """Reversals, samples at a limit and travel of random commands (dithering across the band,
    saturated runs) equal a plain Python count and NumPy's sum (travel to round-off)."""
    rng = np.random.default_rng(5)
    band, dt = 0.05, 1.0
    for k in (1, 2, 7, 50, 333):
        a = np.clip(rng.normal(0.0, 0.6, (k, 3)), -1.0, 1.0)
        a[: k // 3, 1] = 1.0  # a saturated run
        out = command_chatter(a, dt, reversible=[True, True, False], band=band)
        minutes = k * dt / 60.0
        for j in range(3):
            side = count = 0
            for v in a[:, j]:
                s = 1 if v > band else -1 if v < -band else 0
                if s:
                    count += side != 0 and s != side
                    side = s
            want = count / minutes if j < 2 else 0.0
            assert out["reversals_per_min"][j] == want
            assert out["limit_fraction"][j] == np.mean(np.abs(a[:, j]) >= 1.0 - 1e-6)
            travel = np.abs(np.diff(a[:, j])).sum() / minutes
            assert out["travel_per_min"][j] == pytest.approx(travel, rel=1e-12, abs=1e-15)


@pytest.mark.parametrize("n", [1, 2, 3, 4])
@pytest.mark.parametrize("k", [0, 3, 4, 49, 118, 1285])
def test_runs_computed_together_are_each_run_alone(n, k):
    """The chatter of M runs in one call (the vector env's episode ends) is each run's own
    chatter, bit for bit, whatever M and the number of channels (a masked sum or a stacked
    product would sum in another order for some shapes)."""
    from shipgym.metrics import chatter_rows

    rng = np.random.default_rng(10 * k + n)
    a = rng.uniform(-1.2, 1.2, (5, k, n)).clip(-1.0, 1.0)
    rev = rng.random(n) < 0.7
    together = chatter_rows(a, 0.5, rev)
    for r in range(5):
        alone = command_chatter(a[r], 0.5, reversible=rev)
        for key in CHATTER_KEYS:
            assert np.array_equal(together[key][r], alone[key], equal_nan=True), key


def test_starts_count_stops_and_restarts_and_time_at_zero():
    """Issue 31: a start is the shaft turning again from rest (the command out of the 2 %
    band after a stop, past twice the band), or straight through zero to the other side;
    a stop/start cycle on one side is a start without a reversal."""
    dt = 1.0
    # rest, start ahead, dither at the band's edge (no new start), stop, start ahead again,
    # straight through zero to astern (a reversal and a start), back through the band and up
    x = [0.0, 0.3, 0.5, 0.03, 0.019, 0.03, 0.0, 0.0, 0.2, -0.2, -0.01, 0.03, 0.05]
    out = command_chatter(np.array(x), dt)
    minutes = len(x) * dt / 60.0
    # starts: 0.3 (from rest), 0.2 (after the stop), -0.2 (through zero), 0.05 (after -0.01)
    assert out["starts_per_min"][0] == pytest.approx(4 / minutes)
    assert out["reversals_per_min"][0] == pytest.approx(2 / minutes)
    # at zero: |a| <= 0.02: 0.0, 0.019, 0.0, 0.0, -0.01
    assert out["zero_fraction"][0] == pytest.approx(5 / len(x))
    # a command that idles (5 %) instead of stopping starts once
    idle = [0.0, 0.4, 0.05, 0.05, 0.3, 0.05, 0.6]
    out = command_chatter(np.array(idle), dt)
    assert out["starts_per_min"][0] == pytest.approx(1 / (len(idle) / 60.0))
    assert out["zero_fraction"][0] == pytest.approx(1 / len(idle))
    # a stop/start cycle of period 4 s: a start every cycle, no reversal
    cyc = np.tile([0.0, 0.0, 0.3, 0.3], 30)
    out = command_chatter(cyc, 1.0)
    assert out["starts_per_min"][0] == pytest.approx(30 / 2.0)
    assert out["reversals_per_min"][0] == 0.0 and out["zero_fraction"][0] == 0.5


def test_starts_and_zero_equal_a_plain_count_on_random_commands():
    from shipgym.metrics import START_FACTOR

    rng = np.random.default_rng(8)
    band, dt = 0.05, 1.0
    for k in (1, 2, 7, 50, 333):
        a = np.clip(rng.normal(0.0, 0.1, (k, 2)), -1.0, 1.0)
        out = command_chatter(a, dt, band=band)
        for j in range(2):
            run = starts = 0
            for v in a[:, j]:
                s = 1 if v > 0 else -1
                if abs(v) <= band:
                    run = 0
                elif abs(v) > START_FACTOR * band:
                    starts += run != s
                    run = s
                elif run != s:
                    run = 0
            assert out["starts_per_min"][j] == starts / (k * dt / 60.0)
            assert out["zero_fraction"][j] == np.mean(np.abs(a[:, j]) <= band)
