"""The one rotation convention of the suite, and every conversion within it.

The library convention (stated here once; every other module imports it)
-------------------------------------------------------------------------
* **Quaternions** are Hamilton, scalar first, ``q = [w, x, y, z]``. A unit ``q`` rotates *body to navigation
  frame*: ``v_n = q ⊗ (0, v_b) ⊗ q*``, and ``C_bn = quat_to_dcm(q)`` is the matching direction cosine matrix
  (``v_n = C_bn @ v_b``; its columns are the body axes written in navigation coordinates).
* **Euler angles** are ``euler = [roll φ, pitch θ, yaw ψ]`` in radians, aerospace Z-Y-X (yaw, then pitch about the
  new y, then roll about the newest x): ``C_bn = Rz(ψ) @ Ry(θ) @ Rx(φ)`` with the *active* elementary matrices
  :func:`rot_x`, :func:`rot_y`, :func:`rot_z`.
* **Navigation frame** NED by default (x North, y East, z Down; positive yaw turns the nose from North to East,
  positive pitch is nose up, positive roll is right wing down). ENU is supported by :func:`dcm_nav_swap` /
  :func:`quat_nav_swap`, which re-express the same attitude in the other navigation frame (the body frame is
  untouched: it is whatever the sensor's axes are).
* Angles are radians everywhere in the library; degrees appear only at the display edge.

Every function accepts a leading batch axis: ``euler`` of shape ``(N, 3)`` gives ``(N, 3, 3)`` matrices, and so on.

Each seed writes rotations its own way; :mod:`fusionlab.conventions` states how each differs and holds the
functions that convert a seed's convention to this one at the seed's edge (nothing in this module is a seed's
convention). The passive elementary matrices :func:`frame_rot_x` ... :func:`frame_rot_z` are here because they are
plain conversions (``rot_x(angle).T``) that several seeds print.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from . import validate

__all__ = [
    "skew",
    "rot_x",
    "rot_y",
    "rot_z",
    "frame_rot_x",
    "frame_rot_y",
    "frame_rot_z",
    "euler_to_dcm",
    "dcm_to_euler",
    "sequence_to_dcm",
    "dcm_to_sequence",
    "dcm_to_quat",
    "quat_to_dcm",
    "euler_to_quat",
    "quat_to_euler",
    "quat_multiply",
    "quat_conjugate",
    "quat_normalize",
    "quat_rotate",
    "quat_angle_between",
    "rotvec_to_quat",
    "quat_to_rotvec",
    "rodrigues_dcm",
    "dcm_renormalize",
    "is_rotation",
    "euler_rates_matrix",
    "body_rates_matrix",
    "integrate_gyro_dcm",
    "integrate_gyro_quat",
    "NED_ENU",
    "dcm_nav_swap",
    "quat_nav_swap",
]

# ----------------------------------------------------------------------------------------------------------------
# Building blocks
# ----------------------------------------------------------------------------------------------------------------


def skew(v: ArrayLike) -> np.ndarray:
    """Cross-product matrix: ``skew(v) @ u == np.cross(v, u)``.

    Parameters
    ----------
    v : array_like, shape (..., 3)
        The vectors (any unit).

    Returns
    -------
    ndarray, shape (..., 3, 3)
        The skew-symmetric matrices; seed 000 eq 3.50 (Ω) and 3.47 (δΨ) are this matrix of ω and of the small
        angles.

    Examples
    --------
    >>> from fusionlab import rotations
    >>> rotations.skew([1.0, 2.0, 3.0])
    array([[ 0., -3.,  2.],
           [ 3.,  0., -1.],
           [-2.,  1.,  0.]])
    """
    v = validate.vectors(v, "v")
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    o = np.zeros_like(x)
    return np.stack([np.stack([o, -z, y], -1), np.stack([z, o, -x], -1), np.stack([-y, x, o], -1)], -2)


def _elementary(angle, name, axis):
    return _elem(validate.angles_rad(angle, name), axis)


def _elem(a, axis):
    """The active elementary rotation about ``axis`` of already checked angles ``a`` (rad)."""
    c, s = np.cos(a), np.sin(a)
    o, i = np.zeros_like(a), np.ones_like(a)
    rows = {
        0: [[i, o, o], [o, c, -s], [o, s, c]],
        1: [[c, o, s], [o, i, o], [-s, o, c]],
        2: [[c, -s, o], [s, c, o], [o, o, i]],
    }[axis]
    return np.stack([np.stack(r, -1) for r in rows], -2)


def rot_x(angle: float | ArrayLike) -> np.ndarray:
    """Active rotation by ``angle`` (rad) about x: turns a vector counter-clockwise seen from +x.

    Parameters
    ----------
    angle : float or array_like, shape (...)
        Rotation angle, rad.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        The rotation matrices.
    """
    return _elementary(angle, "angle", 0)


def rot_y(angle: float | ArrayLike) -> np.ndarray:
    """Active rotation by ``angle`` (rad) about y.

    Parameters
    ----------
    angle : float or array_like, shape (...)
        Rotation angle, rad.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        The rotation matrices.
    """
    return _elementary(angle, "angle", 1)


def rot_z(angle: float | ArrayLike) -> np.ndarray:
    """Active rotation by ``angle`` (rad) about z.

    Parameters
    ----------
    angle : float or array_like, shape (...)
        Rotation angle, rad.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        The rotation matrices.

    Examples
    --------
    Turning x by 90° about z gives y:

    >>> import numpy as np
    >>> from fusionlab import rotations
    >>> np.round(rotations.rot_z(np.pi / 2) @ [1.0, 0.0, 0.0], 12) + 0.0     # + 0.0 prints -0.0 as 0.0
    array([0., 1., 0.])
    """
    return _elementary(angle, "angle", 2)


def frame_rot_x(angle: float | ArrayLike) -> np.ndarray:
    """Passive (frame) rotation about x, as seed 000 eq 3.38 and seed 001 §5 print it: ``rot_x(angle).T``.

    Parameters
    ----------
    angle : float or array_like, shape (...)
        Rotation angle of the frame, rad.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        The frame rotation matrices.
    """
    return np.swapaxes(rot_x(angle), -1, -2)


def frame_rot_y(angle: float | ArrayLike) -> np.ndarray:
    """Passive (frame) rotation about y, seed 000 eq 3.37 / seed 001 §4: ``rot_y(angle).T``.

    Parameters
    ----------
    angle : float or array_like, shape (...)
        Rotation angle of the frame, rad.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        The frame rotation matrices.
    """
    return np.swapaxes(rot_y(angle), -1, -2)


def frame_rot_z(angle: float | ArrayLike) -> np.ndarray:
    """Passive (frame) rotation about z, seed 000 eq 3.36 / seed 001 §3: ``rot_z(angle).T``.

    Parameters
    ----------
    angle : float or array_like, shape (...)
        Rotation angle of the frame, rad.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        The frame rotation matrices.
    """
    return np.swapaxes(rot_z(angle), -1, -2)


# ----------------------------------------------------------------------------------------------------------------
# Euler angles, DCM, quaternion
# ----------------------------------------------------------------------------------------------------------------


def euler_to_dcm(euler: ArrayLike) -> np.ndarray:
    """Body→navigation DCM from aerospace Z-Y-X Euler angles (seed 000 eq 3.40; seed 004 eq for C_b^n).

    Parameters
    ----------
    euler : array_like, shape (..., 3)
        ``[roll, pitch, yaw]``, rad.

    Returns
    -------
    C_bn : ndarray, shape (..., 3, 3)
        ``Rz(yaw) @ Ry(pitch) @ Rx(roll)``, body→navigation.

    Examples
    --------
    A yaw of 90° turns the nose from North to East: the body x axis, written in NED, is East.

    >>> import numpy as np
    >>> from fusionlab import rotations
    >>> C_bn = rotations.euler_to_dcm([0.0, 0.0, np.pi / 2])
    >>> np.round(C_bn @ [1.0, 0.0, 0.0], 12) + 0.0                 # + 0.0 prints -0.0 as 0.0
    array([0., 1., 0.])
    """
    e = validate.euler_rad(euler, "euler")
    return _elem(e[..., 2], 2) @ _elem(e[..., 1], 1) @ _elem(e[..., 0], 0)  # (000 eq 3.40): Rz Ry Rx


def dcm_to_euler(C_bn: ArrayLike, yaw_at_lock: float = 0.0, lock_tol: float = 1e-9) -> np.ndarray:
    """Euler angles ``[roll, pitch, yaw]`` (rad) of a body→navigation DCM, correct at gimbal lock.

    Away from lock (seed 000 eqs 3.69, 3.72, 3.75): ``θ = -asin(r31)``, ``φ = atan2(r32, r33)``,
    ``ψ = atan2(r21, r11)``. At ``cos θ = 0`` only one combination of roll and yaw is observable; the yaw is then
    set to ``yaw_at_lock`` and the roll follows from the *corrected* seed 000 eqs 3.79/3.81 (the thesis prints the
    two cases swapped):

    * θ = +90°: ``φ = ψ + atan2(r12, r13)``   (only φ - ψ is observable)
    * θ = -90°: ``φ = -ψ + atan2(-r12, -r13)`` (only φ + ψ is observable)

    Parameters
    ----------
    C_bn : array_like, shape (..., 3, 3)
        A body→navigation rotation matrix (checked: orthonormal with det +1 within 0.05, so a slightly drifted DCM
        is read, a reflection or a zero matrix is refused).
    yaw_at_lock : float, default 0.0
        The yaw to report when the pitch is at ±90°, rad.
    lock_tol : float, default 1e-9
        ``cos θ`` below this is treated as gimbal lock.

    Returns
    -------
    ndarray, shape (..., 3)
        ``[roll, pitch, yaw]``, rad.

    Examples
    --------
    At a pitch of 90° a roll of 10° and a yaw of 30° cannot be told apart from a roll of -20° and no yaw: only
    ``φ - ψ`` is observable, and the yaw is reported as ``yaw_at_lock``.

    >>> import numpy as np
    >>> from fusionlab import rotations
    >>> C_bn = rotations.euler_to_dcm(np.radians([10.0, 90.0, 30.0]))
    >>> np.round(np.degrees(rotations.dcm_to_euler(C_bn)), 6) + 0.0
    array([-20.,  90.,   0.])
    """
    C = validate.rotation(C_bn, "C_bn", tol=0.05)  # a drifted DCM still reads (to ~2°); a reflection does not
    yaw_at_lock = validate.scalar(validate.angles_rad(yaw_at_lock, "yaw_at_lock"), "yaw_at_lock")
    lock_tol = validate.positive(lock_tol, "lock_tol")
    r11, r21, r31 = C[..., 0, 0], C[..., 1, 0], C[..., 2, 0]
    cos_pitch = np.hypot(r11, r21)
    pitch = np.arctan2(-r31, cos_pitch)  # (000 eq 3.69), robust near ±1
    lock = cos_pitch < lock_tol
    roll = np.arctan2(C[..., 2, 1], C[..., 2, 2])  # (000 eq 3.72)
    yaw = np.arctan2(r21, r11)  # (000 eq 3.75)
    if np.any(lock):
        r12, r13 = C[..., 0, 1], C[..., 0, 2]
        up = r31 < 0  # θ = +90° has r31 = -1
        roll_up = yaw_at_lock + np.arctan2(r12, r13)  # (000 eq 3.81, corrected)
        roll_down = -yaw_at_lock + np.arctan2(-r12, -r13)  # (000 eq 3.79, corrected)
        roll = np.where(lock, _wrap(np.where(up, roll_up, roll_down)), roll)
        yaw = np.where(lock, yaw_at_lock, yaw)
    return np.stack([roll, pitch, yaw], -1)


def sequence_to_dcm(angles: ArrayLike, seq: str) -> np.ndarray:
    """DCM of an intrinsic rotation sequence: ``seq='ZYX'`` with angles ``(a1, a2, a3)`` is
    ``R_Z(a1) @ R_Y(a2) @ R_X(a3)`` -- rotate about Z, then about the *new* Y, then the newest X.

    ``sequence_to_dcm([yaw, pitch, roll], 'ZYX') == euler_to_dcm([roll, pitch, yaw])``.

    Parameters
    ----------
    angles : array_like, shape (..., 3)
        The three angles in the order the rotations are applied, rad.
    seq : str
        Three letters from 'XYZ', e.g. 'XYZ', 'ZXY', 'YXZ' (consecutive letters must differ).

    Returns
    -------
    ndarray, shape (..., 3, 3)
        The rotation matrices.
    """
    a = validate.vectors(angles, "angles")  # any magnitude: Lab 01's check tries an answer both ways
    _check_seq(seq)
    ax = {"X": 0, "Y": 1, "Z": 2}
    return _elem(a[..., 0], ax[seq[0]]) @ _elem(a[..., 1], ax[seq[1]]) @ _elem(a[..., 2], ax[seq[2]])


def dcm_to_sequence(C: ArrayLike, seq: str) -> np.ndarray:
    """Angles (rad) of the intrinsic sequence ``seq`` that gives rotation ``C`` (inverse of :func:`sequence_to_dcm`).

    Uses ``scipy.spatial.transform.Rotation`` (upper-case sequences are intrinsic there too); the middle angle is
    in [-90°, 90°] for Tait-Bryan sequences.

    Parameters
    ----------
    C : array_like, shape (..., 3, 3)
        Rotation matrices (orthonormal with det +1 within 1e-6).
    seq : str
        Three letters from 'XYZ' (consecutive letters must differ).

    Returns
    -------
    ndarray, shape (..., 3)
        The angles in the order of ``seq``, rad.
    """
    from scipy.spatial.transform import Rotation

    C = validate.matrices(C, "C")
    validate.rotation(C, "C")
    _check_seq(seq)
    return Rotation.from_matrix(C).as_euler(seq)


def _check_seq(seq):
    if not (isinstance(seq, str) and len(seq) == 3 and set(seq) <= set("XYZ") and seq[0] != seq[1] != seq[2]):
        raise ValueError(
            f"seq must be three axis letters from 'XYZ' with no letter twice in a row, e.g. 'ZYX'; got {seq!r}"
        )


def _wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


def quat_to_dcm(q: ArrayLike) -> np.ndarray:
    """Body→navigation DCM ``C_bn`` of a unit quaternion ``[w, x, y, z]`` (seed 001 quaternion note §3 matrix).

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Unit quaternions ``[w, x, y, z]``, body→navigation.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``C_bn``.
    """
    q = validate.quaternions(q, "q")
    w, x, y, z = (q[..., i] for i in range(4))
    return np.stack(
        [
            np.stack([w * w + x * x - y * y - z * z, 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), w * w - x * x + y * y - z * z, 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), w * w - x * x - y * y + z * z], -1),
        ],
        -2,
    )


def dcm_to_quat(C_bn: ArrayLike) -> np.ndarray:
    """Unit quaternion ``[w, x, y, z]`` with ``w >= 0`` of a rotation matrix (Shepperd's method: the largest of
    ``w, x, y, z`` is found from the trace/diagonal first, so there is no division by a small number).

    Parameters
    ----------
    C_bn : array_like, shape (..., 3, 3)
        A rotation matrix (checked: orthonormal with det +1 within 1e-6).

    Returns
    -------
    ndarray, shape (..., 4)
        Unit quaternions ``[w, x, y, z]`` with ``w >= 0``.
    """
    C = validate.matrices(C_bn, "C_bn")
    validate.rotation(C, "C_bn")
    tr = np.trace(C, axis1=-2, axis2=-1)
    d = np.stack([tr, C[..., 0, 0], C[..., 1, 1], C[..., 2, 2]], -1)
    k = np.argmax(d, axis=-1)
    # four candidate quaternions, each computed from the largest component in its own row
    cand = np.stack(
        [
            np.stack(
                [1 + tr, C[..., 2, 1] - C[..., 1, 2], C[..., 0, 2] - C[..., 2, 0], C[..., 1, 0] - C[..., 0, 1]], -1
            ),
            np.stack(
                [
                    C[..., 2, 1] - C[..., 1, 2],
                    1 + 2 * C[..., 0, 0] - tr,
                    C[..., 0, 1] + C[..., 1, 0],
                    C[..., 0, 2] + C[..., 2, 0],
                ],
                -1,
            ),
            np.stack(
                [
                    C[..., 0, 2] - C[..., 2, 0],
                    C[..., 0, 1] + C[..., 1, 0],
                    1 + 2 * C[..., 1, 1] - tr,
                    C[..., 1, 2] + C[..., 2, 1],
                ],
                -1,
            ),
            np.stack(
                [
                    C[..., 1, 0] - C[..., 0, 1],
                    C[..., 0, 2] + C[..., 2, 0],
                    C[..., 1, 2] + C[..., 2, 1],
                    1 + 2 * C[..., 2, 2] - tr,
                ],
                -1,
            ),
        ],
        -2,
    )
    q = np.take_along_axis(cand, k[..., None, None], axis=-2)[..., 0, :]
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return np.where(q[..., :1] < 0, -q, q)


def euler_to_quat(euler: ArrayLike) -> np.ndarray:
    """Quaternion of Z-Y-X Euler angles: ``q_z(ψ) ⊗ q_y(θ) ⊗ q_x(φ)`` (same rotation as :func:`euler_to_dcm`).

    Parameters
    ----------
    euler : array_like, shape (..., 3)
        ``[roll, pitch, yaw]``, rad.

    Returns
    -------
    ndarray, shape (..., 4)
        Unit quaternions ``[w, x, y, z]``, body→navigation.

    Examples
    --------
    >>> import numpy as np
    >>> from fusionlab import rotations
    >>> q = rotations.euler_to_quat(np.radians([10.0, 20.0, 30.0]))
    >>> np.round(np.degrees(rotations.quat_to_euler(q)), 9)           # and back
    array([10., 20., 30.])
    """
    e = validate.euler_rad(euler, "euler")
    h = e / 2
    o = np.zeros_like(h[..., 0])
    qx = np.stack([np.cos(h[..., 0]), np.sin(h[..., 0]), o, o], -1)
    qy = np.stack([np.cos(h[..., 1]), o, np.sin(h[..., 1]), o], -1)
    qz = np.stack([np.cos(h[..., 2]), o, o, np.sin(h[..., 2])], -1)
    return quat_multiply(quat_multiply(qz, qy), qx)


def quat_to_euler(q: ArrayLike, yaw_at_lock: float = 0.0) -> np.ndarray:
    """Euler angles ``[roll, pitch, yaw]`` (rad) of a unit quaternion; gimbal-lock aware (see :func:`dcm_to_euler`).

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Unit quaternions ``[w, x, y, z]``, body→navigation.
    yaw_at_lock : float, default 0.0
        The yaw to report when the pitch is at ±90°, rad.

    Returns
    -------
    ndarray, shape (..., 3)
        ``[roll, pitch, yaw]``, rad.
    """
    return dcm_to_euler(quat_to_dcm(q), yaw_at_lock=yaw_at_lock)


def quat_multiply(p: ArrayLike, q: ArrayLike) -> np.ndarray:
    """Hamilton product ``p ⊗ q`` of scalar-first quaternions (seed 001 quaternion note §2). Shapes broadcast.

    Parameters
    ----------
    p : array_like, shape (..., 4)
        Left factor ``[w, x, y, z]`` (need not be unit).
    q : array_like, shape (..., 4)
        Right factor ``[w, x, y, z]`` (need not be unit).

    Returns
    -------
    ndarray, shape (..., 4)
        ``p ⊗ q``; with unit factors, the rotation ``q`` followed by ``p``.

    Examples
    --------
    The product does not commute: ``i ⊗ j = k`` but ``j ⊗ i = -k``.

    >>> from fusionlab import rotations
    >>> i, j = [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]
    >>> rotations.quat_multiply(i, j), rotations.quat_multiply(j, i)
    (array([0., 0., 0., 1.]), array([ 0.,  0.,  0., -1.]))
    """
    p = validate.array(p, "p", shape=(4,))
    q = validate.array(q, "q", shape=(4,))
    validate.broadcast({"p": 1, "q": 1}, p=p, q=q)
    pw, px, py, pz = (p[..., i] for i in range(4))
    qw, qx, qy, qz = (q[..., i] for i in range(4))
    return np.stack(
        [
            pw * qw - px * qx - py * qy - pz * qz,
            pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx,
            pw * qz + px * qy - py * qx + pz * qw,
        ],
        -1,
    )


def quat_conjugate(q: ArrayLike) -> np.ndarray:
    """``q* = [w, -x, -y, -z]``: the inverse rotation of a unit quaternion.

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Quaternions ``[w, x, y, z]``.

    Returns
    -------
    ndarray, shape (..., 4)
        The conjugates.
    """
    q = validate.array(q, "q", shape=(4,))
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def quat_normalize(q: ArrayLike) -> np.ndarray:
    """``q / |q|``; raises for a zero quaternion (it encodes no rotation).

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Quaternions ``[w, x, y, z]``, non-zero.

    Returns
    -------
    ndarray, shape (..., 4)
        Unit quaternions.
    """
    q = validate.array(q, "q", shape=(4,))
    n = np.linalg.norm(q, axis=-1, keepdims=True)
    if np.any(n < 1e-12):
        raise ValueError("q must be non-zero to be normalised; got a quaternion of norm 0")
    return q / n


def quat_rotate(q: ArrayLike, v: ArrayLike) -> np.ndarray:
    """Rotate body vectors into the navigation frame: ``v_n = q ⊗ (0, v_b) ⊗ q*``.

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Unit quaternions ``[w, x, y, z]``, body→navigation (batch shape broadcasts with ``v``'s).
    v : array_like, shape (..., 3)
        Body vectors (any unit).

    Returns
    -------
    ndarray, shape (..., 3)
        The vectors in navigation coordinates, same unit.

    Examples
    --------
    >>> import numpy as np
    >>> from fusionlab import rotations
    >>> q = rotations.euler_to_quat([0.0, 0.0, np.pi / 2])             # yaw 90°
    >>> np.round(rotations.quat_rotate(q, [1.0, 0.0, 0.0]), 12) + 0.0   # the same as euler_to_dcm's
    array([0., 1., 0.])
    """
    q = validate.quaternions(q, "q")
    v = validate.vectors(v, "v")
    validate.broadcast({"q": 1, "v": 1}, q=q, v=v)
    v4 = np.concatenate([np.zeros(v.shape[:-1] + (1,)), v], -1)
    return quat_multiply(quat_multiply(q, v4), quat_conjugate(q))[..., 1:]


def quat_angle_between(q1: ArrayLike, q2: ArrayLike) -> float | np.ndarray:
    """Angle (rad, in [0, π]) of the rotation that takes attitude ``q1`` to ``q2``; sign of q does not matter.

    Parameters
    ----------
    q1 : array_like, shape (..., 4)
        Unit quaternions ``[w, x, y, z]`` (batch shape broadcasts with ``q2``'s).
    q2 : array_like, shape (..., 4)
        Unit quaternions ``[w, x, y, z]``.

    Returns
    -------
    float or ndarray, shape (...)
        Angle, rad.

    Examples
    --------
    >>> import numpy as np
    >>> from fusionlab import rotations
    >>> q = rotations.euler_to_quat(np.radians([0.0, 0.0, 30.0]))
    >>> round(float(np.degrees(rotations.quat_angle_between([1.0, 0.0, 0.0, 0.0], -q))), 9)   # -q: the same attitude
    30.0
    """
    q1 = validate.quaternions(q1, "q1")
    q2 = validate.quaternions(q2, "q2")
    validate.broadcast({"q1": 1, "q2": 1}, q1=q1, q2=q2)
    d = quat_multiply(quat_conjugate(q1), q2)  # q1* ⊗ q2: the relative rotation
    return 2 * np.arctan2(np.linalg.norm(d[..., 1:], axis=-1), np.abs(d[..., 0]))  # exact near 0, unlike acos


# ----------------------------------------------------------------------------------------------------------------
# Rotation vectors and attitude propagation
# ----------------------------------------------------------------------------------------------------------------


def rotvec_to_quat(sigma: ArrayLike, order: str = "exact") -> np.ndarray:
    """Quaternion of a rotation vector ``σ`` (axis × angle, rad).

    ``order='exact'``: ``[cos(s/2), sin(s/2) σ/s]`` with ``s = |σ|`` (series near 0).
    ``order='first'``: the small-angle form ``[1, σ/2]`` -- *not* unit length; its norm error is ``s²/8``.

    Parameters
    ----------
    sigma : array_like, shape (..., 3)
        Rotation vectors (unit axis × angle), rad; an angle over one turn (2π) is refused as degrees.
    order : {'exact', 'first'}, default 'exact'
        The exact quaternion or its small-angle form.

    Returns
    -------
    ndarray, shape (..., 4)
        Quaternions ``[w, x, y, z]`` (unit for ``'exact'``).

    Examples
    --------
    >>> import numpy as np
    >>> from fusionlab import rotations
    >>> np.round(rotations.rotvec_to_quat([0.0, 0.0, np.pi]), 12)          # half a turn about z
    array([0., 0., 0., 1.])
    >>> q = rotations.rotvec_to_quat([0.0, 0.0, 0.1], order="first")
    >>> round(float(np.linalg.norm(q)) - 1, 6)                 # norm error ≈ s²/8 = 0.00125
    0.001249
    """
    sigma = validate.rotation_vectors(sigma, "sigma")
    if order == "first":
        return np.concatenate([np.ones(sigma.shape[:-1] + (1,)), sigma / 2], -1)
    if order != "exact":
        raise ValueError(f"order must be 'exact' or 'first'; got {order!r}")
    s = np.linalg.norm(sigma, axis=-1, keepdims=True)
    small = s < 1e-6
    s_ = np.where(small, 1.0, s)
    k = np.where(small, 0.5 - s**2 / 48, np.sin(s_ / 2) / s_)  # sin(s/2)/s
    return np.concatenate([np.cos(s / 2), k * sigma], -1)


def quat_to_rotvec(q: ArrayLike) -> np.ndarray:
    """Rotation vector (rad) of a unit quaternion, angle in [0, π] (``q`` and ``-q`` give the same answer).

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Unit quaternions ``[w, x, y, z]``.

    Returns
    -------
    ndarray, shape (..., 3)
        Rotation vectors (unit axis × angle), rad.
    """
    q = validate.quaternions(q, "q")
    q = np.where(q[..., :1] < 0, -q, q)
    v = q[..., 1:]
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    angle = 2 * np.arctan2(n, q[..., :1])
    small = n < 1e-12
    scale = np.where(small, 2.0 / np.where(q[..., :1] == 0, 1, q[..., :1]), angle / np.where(small, 1.0, n))
    return scale * v


def rodrigues_dcm(sigma: ArrayLike, order: str = "exact") -> np.ndarray:
    """DCM increment ``A`` for a body rotation vector over one step: ``C_bn(t+dt) = C_bn(t) @ A``.

    ``order='exact'`` is Rodrigues' formula, seed 000 eq 3.54 **corrected**:
    ``A = I + (sin s / s) B + ((1 - cos s) / s²) B²`` with ``B = skew(σ)``, ``s = |σ|`` -- the thesis prints
    ``(1 - cos s)/s``. ``order='first'`` is eq 3.55, ``A = I + B``; ``order='second'`` adds ``B²/2``.

    Parameters
    ----------
    sigma : array_like, shape (..., 3)
        Body rotation vector over the step (body rate × dt), rad; an angle over one turn (2π) is refused as
        degrees.
    order : {'exact', 'second', 'first'}, default 'exact'
        Rodrigues' formula, or its expansion to second or first order in ``B``.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        The increments ``A``.

    Examples
    --------
    The first-order increment ``I + B`` of a 0.1 rad turn about z:

    >>> from fusionlab import rotations
    >>> rotations.rodrigues_dcm([0.0, 0.0, 0.1], order="first")
    array([[ 1. , -0.1,  0. ],
           [ 0.1,  1. ,  0. ],
           [ 0. ,  0. ,  1. ]])
    """
    sigma = validate.rotation_vectors(sigma, "sigma")
    B = skew(sigma)  # (000 eq 3.53)
    eye = np.broadcast_to(np.eye(3), B.shape)
    if order == "first":
        return eye + B  # (000 eq 3.55)
    if order == "second":
        return eye + B + B @ B / 2
    if order != "exact":
        raise ValueError(f"order must be 'exact', 'second' or 'first'; got {order!r}")
    s = np.linalg.norm(sigma, axis=-1)[..., None, None]
    small = s < 1e-6
    s_ = np.where(small, 1.0, s)
    a = np.where(small, 1 - s**2 / 6, np.sin(s_) / s_)
    b = np.where(small, 0.5 - s**2 / 24, (1 - np.cos(s_)) / s_**2)  # printed: (1 - cos s)/s
    return eye + a * B + b * (B @ B)  # (000 eq 3.54, corrected)


def dcm_renormalize(C: ArrayLike, axis: str = "columns") -> np.ndarray:
    """Re-orthonormalise a drifting DCM (seed 000 eqs 3.59-3.65; Premerlani & Bizard).

    Take the first two rows (``axis='rows'``, as the thesis text does) or columns (as its lab code does),
    share their dot-product error half each (3.59-3.61), rebuild the third as their cross product (3.62) and scale
    each by the first-order factor ``(3 - r·r)/2`` (3.63-3.65). Either choice is valid for a rotation matrix.

    Parameters
    ----------
    C : array_like, shape (..., 3, 3)
        Nearly orthonormal matrices (within 0.25; a zero or reflected matrix has no fix and is refused).
    axis : {'columns', 'rows'}, default 'columns'
        Which pair to correct: the first two columns (the thesis' lab code) or rows (its text).

    Returns
    -------
    ndarray, shape (..., 3, 3)
        The corrected matrices, orthonormal to first order in the error.
    """
    C = validate.rotation(C, "C", tol=0.25)  # drifted, not degenerate: a zero or reflected C has no fix
    if axis not in ("columns", "rows"):
        raise ValueError(f"axis must be 'columns' or 'rows'; got {axis!r}")
    M = np.swapaxes(C, -1, -2) if axis == "columns" else C
    r1, r2 = M[..., 0, :], M[..., 1, :]
    err = np.sum(r1 * r2, axis=-1, keepdims=True)  # (000 eq 3.59)
    r1n = r1 - err / 2 * r2  # (000 eq 3.60)
    r2n = r2 - err / 2 * r1  # (000 eq 3.61)
    r3n = np.cross(r1n, r2n)  # (000 eq 3.62)
    out = np.stack([(3 - np.sum(r * r, axis=-1, keepdims=True)) / 2 * r for r in (r1n, r2n, r3n)], -2)  # (3.63-65)
    return np.swapaxes(out, -1, -2) if axis == "columns" else out


def is_rotation(C: ArrayLike, tol: float = 1e-6) -> bool | np.ndarray:
    """True where ``C`` is orthonormal with determinant +1 within ``tol``.

    Parameters
    ----------
    C : array_like, shape (..., 3, 3)
        The matrices.
    tol : float, default 1e-6
        Allowed deviation of ``C Cᵀ`` from I (largest entry) and of det C from 1.

    Returns
    -------
    bool or ndarray of bool, shape (...)
        Whether each matrix is a rotation.
    """
    C = validate.matrices(C, "C")
    tol = validate.scalar(tol, "tol", positive=True)
    ortho = np.max(np.abs(C @ np.swapaxes(C, -1, -2) - np.eye(3)), axis=(-2, -1))
    return (ortho < tol) & (np.abs(np.linalg.det(C) - 1) < tol)


def _roll_pitch(roll, pitch):
    r = validate.angles_rad(roll, "roll")
    p = validate.angles_rad(pitch, "pitch", limit=np.pi + 1e-9)
    validate.broadcast(roll=r, pitch=p)
    return r, p


def euler_rates_matrix(roll: float | ArrayLike, pitch: float | ArrayLike) -> np.ndarray:
    """Matrix ``D(φ, θ)`` mapping body rates ``(p, q, r)`` to Euler-angle rates (seed 001 Euler note §7).

    ``[φ̇, θ̇, ψ̇] = D @ [p, q, r]``. It does not depend on yaw (the note's ``D(φ, θ, ψ)`` is a misnomer) and both
    its first row (tan θ) and last row (1/cos θ) diverge at θ = ±90°.

    Parameters
    ----------
    roll : float or array_like, shape (...)
        Roll φ, rad.
    pitch : float or array_like, shape (...)
        Pitch θ, rad (broadcasts with ``roll``).

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``D(φ, θ)``.
    """
    r, p = _roll_pitch(roll, pitch)
    sr, cr, tp, cp = np.sin(r), np.cos(r), np.tan(p), np.cos(p)
    o, i = np.zeros_like(sr * cp), np.ones_like(sr * cp)
    return np.stack(
        [np.stack([i, sr * tp, cr * tp], -1), np.stack([o, cr + o, -sr + o], -1), np.stack([o, sr / cp, cr / cp], -1)],
        -2,
    )  # (001 Euler §7, D)


def body_rates_matrix(roll: float | ArrayLike, pitch: float | ArrayLike) -> np.ndarray:
    """Matrix ``W(φ, θ)`` mapping Euler-angle rates to body rates, the inverse of :func:`euler_rates_matrix`.

    ``[p, q, r] = W @ [φ̇, θ̇, ψ̇]``; ``det W = cos θ`` (not printed in the note; derived in docs/derivations.md §4).

    Parameters
    ----------
    roll : float or array_like, shape (...)
        Roll φ, rad.
    pitch : float or array_like, shape (...)
        Pitch θ, rad (broadcasts with ``roll``).

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``W(φ, θ)``.
    """
    r, p = _roll_pitch(roll, pitch)
    sr, cr, sp, cp = np.sin(r), np.cos(r), np.sin(p), np.cos(p)
    o, i = np.zeros_like(sr * cp), np.ones_like(sr * cp)
    return np.stack(
        [np.stack([i, o, -sp + o], -1), np.stack([o, cr + o, sr * cp], -1), np.stack([o, -sr + o, cr * cp], -1)], -2
    )


def integrate_gyro_dcm(
    C0: ArrayLike, gyr: ArrayLike, dt: float, order: str = "first", renormalize: str | None = "columns"
) -> np.ndarray:
    """Propagate a body→nav DCM with body rates: ``C_{k+1} = C_k @ A(ω_k dt)`` (seed 000 eqs 3.44, 3.54-3.55).

    Parameters
    ----------
    C0 : array_like, shape (3, 3)
        Initial ``C_bn``.
    gyr : array_like, shape (N, 3)
        Body rates, one row per step, rad/s.
    dt : float
        Time step, s, 10 µs – 1 s (a larger value is refused as a sample rate in Hz).
    order : {'first', 'second', 'exact'}, default 'first'
        ``'first'`` (I + B, the thesis lab), ``'second'`` or ``'exact'`` (Rodrigues), see :func:`rodrigues_dcm`.
    renormalize : {'columns', 'rows', None}, default 'columns'
        Apply :func:`dcm_renormalize` after every step (None: never).

    Returns
    -------
    ndarray, shape (N + 1, 3, 3)
        ``C0`` and the attitude after every step.

    Examples
    --------
    One second at 90 °/s about z in 100 steps: the first-order update without renormalisation lets the matrix grow
    (det 1.025), renormalising keeps it a rotation, and only the exact increment reaches the full 90°.

    >>> import numpy as np
    >>> from fusionlab import rotations
    >>> gyr = np.tile(np.radians([0.0, 0.0, 90.0]), (100, 1))
    >>> for order, renorm in [("first", None), ("first", "columns"), ("exact", None)]:
    ...     C = rotations.integrate_gyro_dcm(np.eye(3), gyr, 0.01, order=order, renormalize=renorm)[-1]
    ...     yaw = np.degrees(rotations.dcm_to_euler(C)[2])
    ...     print(f"{order:5s} {renorm!s:7s} det {np.linalg.det(C):.4f} yaw {yaw:.4f}")
    first None    det 1.0250 yaw 89.9926
    first columns det 1.0000 yaw 89.9926
    exact None    det 1.0000 yaw 90.0000
    """
    C = validate.rotation(validate.exact_shape(C0, "C0", (3, 3)), "C0", tol=1e-3)
    gyr = validate.gyro_rad(gyr, "gyr")
    dt = validate.time_step(dt, "dt")
    validate.turn_per_step(gyr, dt, "gyr")
    if renormalize not in (None, "columns", "rows"):
        raise ValueError(f"renormalize must be 'columns', 'rows' or None; got {renormalize!r}")
    A = rodrigues_dcm(gyr * dt, order=order)
    out = np.empty((len(gyr) + 1, 3, 3))
    out[0] = C
    for k in range(len(gyr)):
        C = C @ A[k]  # (000 eq 3.44)
        if renormalize:
            C = dcm_renormalize(C, axis=renormalize)
        out[k + 1] = C
    return out


def integrate_gyro_quat(q0: ArrayLike, gyr: ArrayLike, dt: float) -> np.ndarray:
    """Propagate a body→nav quaternion exactly for piecewise-constant rates: ``q_{k+1} = q_k ⊗ q(ω_k dt)``.

    Parameters
    ----------
    q0 : array_like, shape (4,)
        Initial unit quaternion ``[w, x, y, z]``, body→navigation.
    gyr : array_like, shape (N, 3)
        Body rates, one row per step, rad/s. Refused as °/s when they peak above 50 or have a median above 10, or
        turn more than π in one step; a record in °/s that is mostly at rest passes these (only the accelerometer
        could tell: :func:`fusionlab.validate.gyro_rad` with ``acc``, as ``estimators.run`` does).
    dt : float
        Time step, s, 10 µs – 1 s (a larger value is refused as a sample rate in Hz).

    Returns
    -------
    ndarray, shape (N + 1, 4)
        ``q0`` and the attitude after every step (unit quaternions).

    Examples
    --------
    >>> import numpy as np
    >>> from fusionlab import rotations
    >>> gyr = np.tile(np.radians([0.0, 0.0, 90.0]), (100, 1))            # 1 s at 90 °/s about z
    >>> q = rotations.integrate_gyro_quat([1.0, 0.0, 0.0, 0.0], gyr, 0.01)
    >>> q.shape, np.round(np.degrees(rotations.quat_to_euler(q[-1])), 9) + 0.0
    ((101, 4), array([ 0.,  0., 90.]))
    """
    q = validate.quaternions(q0, "q0")
    if q.shape != (4,):
        raise ValueError(f"q0 must be one quaternion, shape (4,); got {q.shape}")
    gyr = validate.gyro_rad(gyr, "gyr")
    dt = validate.time_step(dt, "dt")
    validate.turn_per_step(gyr, dt, "gyr")
    dq = rotvec_to_quat(gyr * dt)
    out = np.empty((len(gyr) + 1, 4))
    out[0] = q
    w, x, y, z = q
    for k, (a, b, c, d) in enumerate(dq):  # Hamilton product, unrolled for speed
        w, x, y, z = (
            w * a - x * b - y * c - z * d,
            w * b + x * a + y * d - z * c,
            w * c - x * d + y * a + z * b,
            w * d + x * c - y * b + z * a,
        )
        n = (w * w + x * x + y * y + z * z) ** 0.5
        w, x, y, z = w / n, x / n, y / n, z / n
        out[k + 1] = (w, x, y, z)
    return out


# ----------------------------------------------------------------------------------------------------------------
# Navigation frames
# ----------------------------------------------------------------------------------------------------------------

#: Re-expresses navigation coordinates NED ↔ ENU (its own inverse): ``v_enu = NED_ENU @ v_ned``.
NED_ENU = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
_Q_NED_ENU = np.array([0.0, np.sqrt(0.5), np.sqrt(0.5), 0.0])  # the quaternion of NED_ENU


def dcm_nav_swap(C_bn: ArrayLike) -> np.ndarray:
    """The same attitude with the navigation frame changed NED ↔ ENU: ``NED_ENU @ C_bn`` (body axes unchanged).

    Parameters
    ----------
    C_bn : array_like, shape (..., 3, 3)
        Body→navigation rotation matrices (within 0.05 of a rotation).

    Returns
    -------
    ndarray, shape (..., 3, 3)
        The same attitudes, body→(the other navigation frame).
    """
    C = validate.rotation(C_bn, "C_bn", tol=0.05)
    return NED_ENU @ C


def quat_nav_swap(q: ArrayLike) -> np.ndarray:
    """Quaternion form of :func:`dcm_nav_swap` (NED ↔ ENU navigation frame), ``w >= 0``.

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Unit quaternions ``[w, x, y, z]``, body→navigation.

    Returns
    -------
    ndarray, shape (..., 4)
        The same attitudes in the other navigation frame, ``w >= 0``.
    """
    q = validate.quaternions(q, "q")
    out = quat_multiply(_Q_NED_ENU, q)
    return np.where(out[..., :1] < 0, -out, out)
