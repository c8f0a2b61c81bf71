"""Student feedback: visible checks that explain a wrong answer instead of a bare AssertionError.

Each ``check_*`` function runs a student's function or value against the library on a few cases. On success it
prints one line starting with ✓; on failure it raises :class:`Feedback` (an ``AssertionError``) whose message names
the most likely slip: a transposed DCM (body→nav vs nav→body), degrees passed where radians were meant, the
elementary rotations in the wrong order, a passive matrix where an active one was wanted, ``[x, y, z, w]`` quaternion
order, a printed-seed typo. Notebooks call these in the visible test cell right after an exercise
(``checks.check_predict(my_predict)``); the hidden tests compare with the library.

One file per lab, named after the lab's folder (``lab02_kalman_falling_body.py`` holds Lab 02's checks); ``_core.py``
holds :class:`Feedback` and what the checks share. Everything public is re-exported here. ``slips.py`` gives the
slips the checks name identifiers (the grading tools' class report of common slips counts them).

Every lab's locked setup cell imports this package, and through it :mod:`fusionlab.guard` -- first, so that the guard
records numpy, the library and IPython's hooks before any answer cell runs -- and :func:`friendly_errors`, which
turns an unfinished exercise's NotImplementedError or NameError into a line saying what to finish.
"""

from __future__ import annotations

from .. import guard  # noqa: F401  (first: the guard's baseline is taken before anything else of the checks loads)
from . import (
    _core,
    lab00_mems_sensors,
    lab01_euler_rotations,
    lab02_kalman_falling_body,
    lab03_correlation_fusion,
    lab04_ecompass,
    lab05_freescale_kalman,
    lab06_gfimu_aiv,
    lab07_gfimu_constraints,
    lab08_north_finder,
    lab09_dcm_ahrs,
    lab10_gps_ins,
    lab11_real_data,
    lab12_sensor_errors,
    lab13_capstone,
    lab14_phone_imu,
)
from . import slips  # noqa: F401  (the named slips, as data)
from ._core import *  # noqa: F401,F403
from .lab00_mems_sensors import *  # noqa: F401,F403
from .lab01_euler_rotations import *  # noqa: F401,F403
from .lab02_kalman_falling_body import *  # noqa: F401,F403
from .lab03_correlation_fusion import *  # noqa: F401,F403
from .lab04_ecompass import *  # noqa: F401,F403
from .lab05_freescale_kalman import *  # noqa: F401,F403
from .lab06_gfimu_aiv import *  # noqa: F401,F403
from .lab07_gfimu_constraints import *  # noqa: F401,F403
from .lab08_north_finder import *  # noqa: F401,F403
from .lab09_dcm_ahrs import *  # noqa: F401,F403
from .lab10_gps_ins import *  # noqa: F401,F403
from .lab11_real_data import *  # noqa: F401,F403
from .lab12_sensor_errors import *  # noqa: F401,F403
from .lab13_capstone import *  # noqa: F401,F403
from .lab14_phone_imu import *  # noqa: F401,F403

LABS = (
    lab00_mems_sensors,
    lab01_euler_rotations,
    lab02_kalman_falling_body,
    lab03_correlation_fusion,
    lab04_ecompass,
    lab05_freescale_kalman,
    lab06_gfimu_aiv,
    lab07_gfimu_constraints,
    lab08_north_finder,
    lab09_dcm_ahrs,
    lab10_gps_ins,
    lab11_real_data,
    lab12_sensor_errors,
    lab13_capstone,
    lab14_phone_imu,
)
__all__ = [*_core.__all__, *(name for lab in LABS for name in lab.__all__)]

guard._snapshot_new_modules()  # the library as loaded now, before any answer cell: what guard.intact() compares with
