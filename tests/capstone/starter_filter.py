import numpy as np


def estimate(gyr, acc, mag, fs, k_acc=1.0, k_mag=0.5, k_bias=0.0):
    """A complementary filter (Mahony's form): integrate the gyro, pull towards gravity and magnetic north.

    gyr rad/s, acc m/s^2, mag uT, (N, 3) each, in the sensor frame; returns (N, 4) body->ENU [w, x, y, z].
    """
    gyr, acc, mag = (np.asarray(a, dtype=float) for a in (gyr, acc, mag))
    dt = 1.0 / fs
    q = _start(acc[0], mag[0])
    bias = np.zeros(3)
    out = np.empty((len(gyr), 4))
    for k in range(len(gyr)):
        C = _dcm(q)                                    # body -> ENU
        up_b = C[2]                                    # ENU up, seen in the body frame
        a = acc[k] / (np.linalg.norm(acc[k]) + 1e-12)
        e = k_acc * np.cross(a, up_b)                  # tilt error: rotate the estimate towards measured gravity
        h = C @ mag[k]                                 # field in ENU
        b = np.array([0.0, np.hypot(h[0], h[1]), h[2]])   # ... as it should be: north is +y
        w = C.T @ b
        m = mag[k] / (np.linalg.norm(mag[k]) + 1e-12)
        e += k_mag * np.cross(m, w / (np.linalg.norm(w) + 1e-12))
        bias -= k_bias * e * dt
        omega = gyr[k] - bias + e
        q = _step(q, omega * dt)
        out[k] = q
    return out


def _start(a, m):
    up = a / np.linalg.norm(a)
    east = np.cross(m, up)
    east /= np.linalg.norm(east)
    north = np.cross(up, east)
    C = np.vstack([east, north, up])                   # rows: ENU axes in body coordinates, so C is body -> ENU
    return _quat(C)


def _dcm(q):
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _quat(C):
    w = np.sqrt(max(0.0, 1 + C[0, 0] + C[1, 1] + C[2, 2])) / 2
    if w > 0.1:
        return np.array([w, (C[2, 1] - C[1, 2]) / (4 * w), (C[0, 2] - C[2, 0]) / (4 * w), (C[1, 0] - C[0, 1]) / (4 * w)])
    i = int(np.argmax(np.diag(C)))
    j, k = (i + 1) % 3, (i + 2) % 3
    v = np.zeros(3)
    v[i] = np.sqrt(max(0.0, 1 + C[i, i] - C[j, j] - C[k, k])) / 2
    v[j] = (C[j, i] + C[i, j]) / (4 * v[i])
    v[k] = (C[k, i] + C[i, k]) / (4 * v[i])
    w = (C[k, j] - C[j, k]) / (4 * v[i])
    q = np.array([w, *v])
    return q if w >= 0 else -q


def _step(q, sigma):
    angle = np.linalg.norm(sigma)
    if angle < 1e-12:
        return q
    axis = sigma / angle
    dq = np.array([np.cos(angle / 2), *(np.sin(angle / 2) * axis)])
    w1, x1, y1, z1 = q
    w2, x2, y2, z2 = dq
    p = np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                  w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])
    return p / np.linalg.norm(p)
