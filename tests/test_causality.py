"""Every registered filter is causal: its output at sample k uses no sample after k.

A real-time filter cannot know the future, nor a statistic of the whole recording (its median field strength,
the mean of its first half second); a filter that does gets a flattering score on a benchmark. The test: run the
filter on a recording, replace every sample after k by noise (gyro, accelerometer and magnetometer), run it again,
and compare the outputs up to k bit for bit (1e-12). Several k, one inside the first Kalman step and the first
0.5 s, one inside an update block, one in the middle.
"""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import estimators, simulate
from fusionlab.capstone import CAUSAL_NOISE, perturb_future

FS = 286.0  # BROAD's rate: 6 samples per DCM update, 11 per Freescale step


@pytest.fixture(scope="module")
def record():
    rec = simulate.hand_motion_record(seed=5, fs=FS, duration=24.0, still=4.0)
    return rec["gyr"], rec["acc"], rec["mag"] * 100.0  # gauss → µT, as a real magnetometer


@pytest.mark.parametrize("name", sorted(estimators.available()))
def test_the_output_up_to_k_does_not_change_when_later_samples_change(name, record):
    gyr, acc, mag = record
    run = lambda g, a, m: estimators.run(name, gyr=g, acc=a, fs=FS, mag=m, frame="ENU")
    q = run(gyr, acc, mag)
    rng = np.random.default_rng(21)
    n = len(gyr)
    for k in (3, 8, 200, n // 2 + 1):
        g2, a2, m2 = (perturb_future(x, k, s, rng) for x, s in zip((gyr, acc, mag), CAUSAL_NOISE))
        q2 = run(g2, a2, m2)
        assert np.max(np.abs(q2[: k + 1] - q[: k + 1])) <= 1e-12, f"{name}: sample <= {k} changed"
        assert np.max(np.abs(q2[k + 1 :] - q[k + 1 :])) > 1e-6, f"{name}: the perturbation changed nothing"


def test_every_registered_filter_is_covered():
    """The parametrisation above is the registry itself: a new filter is tested the day it registers."""
    assert {
        "gyro",
        "triad",
        "freescale6",
        "freescale9",
        "complementary",
        "correlation",
        "dcm_ahrs",
        "dcm_ahrs6",
    } <= set(estimators.available())
