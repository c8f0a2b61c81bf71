"""The falling body of thesis lab 2 (seed 000 §4.4): its model, the thesis' Kalman filter and its Monte Carlo.

What is here, in the order the lab uses it
-------------------------------------------
* **Part A** (000 §4.4.1): the linear-drag falling body ``dv/dt = -(k/m) v - g``, Euler-discretised exactly as the
  lab prints it (:func:`seed000_labcode_falling_body`, including its 199-step loop), the fixed version on a time
  axis, the closed form, terminal velocity and time constant, and quadratic drag with ``scipy.integrate.solve_ivp``.
* **Part B** (000 §4.4.2): the state-space matrices ``A``, ``B`` and input ``u``; the mass-spring-damper question.
* **Part C** (000 §4.4.3): the lab's printed ``Kalman_Filter`` function (:func:`seed000_labcode_kalman`);
  :class:`ThesisKF` -- the thesis' update-then-project loop (fig 26), written line by line from the equations of
  :mod:`fusionlab.kalman`, with switches for the printed MATLAB code (no state projection, short form) and for
  eq 4.32 as printed (no control term); :func:`simulate_falling_body` and :func:`monte_carlo` (seeded, batched
  with :func:`fusionlab.kalman.kf_batch`, with a progress bar).

The Kalman filter's equations themselves (gain, covariance forms, update, predict, NEES, steady state) are those
of any linear model and live in :mod:`fusionlab.kalman`.

Conventions
-----------
State ``x`` is ``[position (m, up), velocity (m/s, up)]``; the shapes of the filter's matrices are those of
:mod:`fusionlab.kalman`. The thesis' loop order is *update, then project*: the state a step starts with is the
prior for the measurement it receives. Gravity in lab 2 is the thesis' ``g = 9.8`` m/s².

Everything numeric in the lab that the seed does not print (the closed form, the drag constants) is labelled as
an addition in its docstring.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy.integrate import solve_ivp

from . import kalman, validate

__all__ = [
    "LAB2",
    "AIR_DENSITY",
    "SPHERE_CD",
    "SPHERE_AREA",
    "terminal_velocity",
    "time_constant",
    "seed000_labcode_falling_body",
    "falling_body_euler",
    "falling_body_exact",
    "quadratic_terminal_velocity",
    "falling_body_quadratic",
    "falling_body_state_space",
    "mass_spring_damper_ss",
    "seed000_labcode_kalman",
    "ThesisKF",
    "simulate_falling_body",
    "monte_carlo",
]


#: Thesis lab 2 parameters (000 §4.4.1 and §4.4.3), SI units. ``tmax`` is the printed ``TMAX`` (a count of
#: array slots, not seconds); ``mn_std``/``pn_std`` are the printed ``MNstd``/``PNstd``.
LAB2 = dict(k=0.25, m=10.0, g=9.8, dt=0.01, tmax=200, x0=200.0, v0=0.0, mn_std=12.0, pn_std=0.4)

#: Quadratic-drag constants assumed for Part A's question (the thesis gives none): sea-level air, a smooth sphere
#: 25 cm across (C_D of a sphere at these Reynolds numbers), mass 10 kg as in the lab.
AIR_DENSITY = 1.225  # kg/m^3, ISA sea level
SPHERE_CD = 0.47  # -, smooth sphere, Re ~ 1e5
SPHERE_AREA = np.pi * 0.125**2  # m^2, frontal area of a 0.25 m sphere


# ----------------------------------------------------------------------------------------------------------------
# Part A: the falling body (000 §4.4.1)
# ----------------------------------------------------------------------------------------------------------------


def terminal_velocity(k: float, m: float, g: float = 9.8) -> float:
    """Terminal velocity of the linear-drag model, m/s: set ``dv/dt = -(k/m) v - g = 0`` (000 §4.4.1).

    Parameters
    ----------
    k : float
        Linear drag coefficient, kg/s (> 0).
    m : float
        Mass, kg (> 0).
    g : float, optional
        Gravity, m/s², > 0 (the body falls down: a negative g would make it fall upward).

    Returns
    -------
    float
        ``-m g / k`` in m/s (negative: downwards). Lab values: -392 m/s.

    Examples
    --------
    >>> terminal_velocity(0.25, 10.0)
    -392.0
    """
    k, m, g = validate.scalar(k, "k", True), validate.scalar(m, "m", True), validate.scalar(g, "g", True)
    return -m * g / k


def time_constant(k: float, m: float) -> float:
    """Time constant ``τ = m / k`` (s) of the linear-drag model: v approaches terminal as ``exp(-t/τ)``.

    Lab values: 40 s, so the lab's 1.99 s sees only 5 % of the approach.

    Parameters
    ----------
    k : float
        Linear drag coefficient, kg/s (> 0).
    m : float
        Mass, kg (> 0).

    Returns
    -------
    float
        ``τ`` in s.

    Examples
    --------
    >>> time_constant(0.25, 10.0)
    40.0
    """
    return validate.scalar(m, "m", True) / validate.scalar(k, "k", True)


def seed000_labcode_falling_body(
    k: float = 0.25,
    m: float = 10.0,
    g: float = 9.8,
    dt: float = 0.01,
    TMAX: int = 200,
    x0: float = 200.0,
    v0: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Thesis lab 2 Part A code, verbatim (000 §4.4.1 step c), including its bug.

    The printed MATLAB::

        X(1)=x0; V(1)=v0;
        for t=2:TMAX
            X(t)=X(t-1)+(V(t-1))*dt;
            V(t)=V(t-1)+(-(k/m)*(V(t-1))-g)*dt;
        end

    ``TMAX = 200`` is commented "Total Time" but is used as a number of array slots: the loop makes
    ``TMAX - 1 = 199`` steps, 1.99 s of simulated time, not 200 s (``time = 1:dt:TMAX`` is built and never used).
    Final values with the lab's numbers: x = 181.006 m, v = -19.027 m/s.

    Parameters
    ----------
    k : float, optional
        Linear drag coefficient, kg/s.
    m : float, optional
        Mass, kg.
    g : float, optional
        Gravity, m/s², > 0 (the body falls down: a negative g would make it fall upward).
    dt : float, optional
        Time step, s.
    TMAX : int, optional
        The printed ``TMAX`` (array length, not seconds).
    x0 : float, optional
        Start position, m (up).
    v0 : float, optional
        Start velocity, m/s (up).

    Returns
    -------
    X : ndarray, shape (TMAX,)
        Position, m, at sample indices 1..TMAX (MATLAB), 0..TMAX-1 here.
    V : ndarray, shape (TMAX,)
        Velocity, m/s, at the same samples.

    Examples
    --------
    >>> X, V = seed000_labcode_falling_body()
    >>> len(X), round(float(X[-1]), 3), round(float(V[-1]), 3)
    (200, 181.006, -19.027)
    """
    k, m, g = validate.scalar(k, "k", True), validate.scalar(m, "m", True), validate.scalar(g, "g", True)
    dt, x0, v0 = validate.time_step(dt, "dt"), validate.scalar(x0, "x0"), validate.scalar(v0, "v0")
    TMAX = validate.count(TMAX, "TMAX", 1)
    X = np.zeros(TMAX)
    V = np.zeros(TMAX)
    X[0], V[0] = x0, v0
    for t in range(1, TMAX):  # MATLAB: for t=2:TMAX
        X[t] = X[t - 1] + (V[t - 1]) * dt  # (000 §4.4.1, x_t = x_{t-1} + v_{t-1} dt)
        V[t] = V[t - 1] + (-(k / m) * (V[t - 1]) - g) * dt  # (000 §4.4.1, v_t = v_{t-1} - (k/m v + g) dt)
    return X, V


def falling_body_euler(
    duration: float,
    k: float = 0.25,
    m: float = 10.0,
    g: float = 9.8,
    dt: float = 0.01,
    x0: float = 200.0,
    v0: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """The same Euler recurrence as the lab (000 §4.4.1) on a real time axis: the fix of the 199-step loop.

    Runs ``round(duration / dt)`` steps so that the last sample is at ``t = duration`` seconds. No ground: the body
    keeps falling through x = 0 (the thesis' model has no ground either).

    Parameters
    ----------
    duration : float
        Simulated time, s; must be a whole number of steps ``dt``.
    k : float, optional
        Linear drag coefficient, kg/s.
    m : float, optional
        Mass, kg.
    g : float, optional
        Gravity, m/s², > 0 (the body falls down: a negative g would make it fall upward).
    dt : float, optional
        Time step, s.
    x0 : float, optional
        Start position, m (up).
    v0 : float, optional
        Start velocity, m/s (up).

    Returns
    -------
    t : ndarray, shape (N + 1,)
        Sample times, s, with ``N = duration / dt``.
    x : ndarray, shape (N + 1, 2)
        ``[position (m), velocity (m/s)]`` at each ``t``.
    """
    duration, dt = validate.scalar(duration, "duration", True), validate.time_step(dt, "dt")
    k, m, g = validate.scalar(k, "k", True), validate.scalar(m, "m", True), validate.scalar(g, "g", True)
    n = int(round(duration / dt))
    if abs(n * dt - duration) > 1e-9 * max(1.0, duration):
        raise ValueError(f"duration must be a whole number of steps dt = {dt:g} s; got {duration:g} s")
    out = np.empty((n + 1, 2))
    out[0] = validate.scalar(x0, "x0"), validate.scalar(v0, "v0")
    for i in range(n):
        x, v = out[i]
        out[i + 1, 0] = x + v * dt  # (000 §4.4.1)
        out[i + 1, 1] = v + (-(k / m) * v - g) * dt  # (000 §4.4.1)
    return np.arange(n + 1) * dt, out


def falling_body_exact(
    t: ArrayLike, k: float = 0.25, m: float = 10.0, g: float = 9.8, x0: float = 200.0, v0: float = 0.0
) -> np.ndarray:
    """Closed-form solution of ``dv/dt = -(k/m) v - g`` (the lab's continuous model; the closed form is an addition).

    ``v(t) = v_T + (v0 - v_T) e^{-t/τ}``, ``x(t) = x0 + v_T t + (v0 - v_T) τ (1 - e^{-t/τ})`` with
    ``v_T = -m g / k`` and ``τ = m / k``.

    Parameters
    ----------
    t : array_like, shape (...)
        Times, s.
    k : float, optional
        Linear drag coefficient, kg/s.
    m : float, optional
        Mass, kg.
    g : float, optional
        Gravity, m/s², > 0 (the body falls down: a negative g would make it fall upward).
    x0 : float, optional
        Start position, m (up).
    v0 : float, optional
        Start velocity, m/s (up).

    Returns
    -------
    ndarray, shape (..., 2)
        ``[position (m), velocity (m/s)]`` at each time.
    """
    t = validate.array(t, "t")
    vT, tau = terminal_velocity(k, m, g), time_constant(k, m)
    x0, v0 = validate.scalar(x0, "x0"), validate.scalar(v0, "v0")
    decay = np.exp(-t / tau)
    v = vT + (v0 - vT) * decay
    x = x0 + vT * t + (v0 - vT) * tau * (1 - decay)
    return np.stack([x, v], -1)


def quadratic_terminal_velocity(
    m: float = 10.0, g: float = 9.8, rho: float = AIR_DENSITY, C_D: float = SPHERE_CD, area: float = SPHERE_AREA
) -> float:
    """Terminal velocity with quadratic drag ``D = ½ ρ C_D A v²`` (000 §4.4.1 question 1), m/s, negative (down).

    ``m g = ½ ρ C_D A v_T²`` gives ``v_T = -sqrt(2 m g / (ρ C_D A))``. With the module's assumed constants
    (10 kg sphere, 25 cm across, sea-level air): -83.3 m/s.

    Parameters
    ----------
    m : float, optional
        Mass, kg.
    g : float, optional
        Gravity, m/s², > 0 (the body falls down: a negative g would make it fall upward).
    rho : float, optional
        Air density, kg/m³.
    C_D : float, optional
        Drag coefficient (dimensionless).
    area : float, optional
        Frontal area, m².

    Returns
    -------
    float
        ``v_T`` in m/s (negative: downwards).
    """
    m, g = validate.scalar(m, "m", True), validate.scalar(g, "g", True)
    rho, C_D = validate.scalar(rho, "rho", True), validate.scalar(C_D, "C_D", True)
    area = validate.scalar(area, "area", True)
    return -np.sqrt(2 * m * g / (rho * C_D * area))


def falling_body_quadratic(
    duration: float,
    x0: float = 200.0,
    v0: float = 0.0,
    m: float = 10.0,
    g: float = 9.8,
    rho: float = AIR_DENSITY,
    C_D: float = SPHERE_CD,
    area: float = SPHERE_AREA,
    stop_at_ground: bool = True,
    t_eval: ArrayLike | None = None,
):
    """Falling body with quadratic drag, solved with ``scipy.integrate.solve_ivp`` (RK45, MATLAB's ``ode45``).

    000 §4.4.1 questions 1-2: with ``F_Drag = ½ ρ C_D A v²`` acting against the motion,
    ``m dv/dt = -m g - ½ ρ C_D A |v| v`` and ``dx/dt = v``. The thesis prints ``D = ½ ρ A v²`` (C_D dropped) and
    gives no values; the defaults here are stated in :data:`AIR_DENSITY`, :data:`SPHERE_CD`, :data:`SPHERE_AREA`.

    Parameters
    ----------
    duration : float
        End of the integration, s.
    x0 : float, optional
        Start position, m.
    v0 : float, optional
        Start velocity, m/s (up positive).
    m : float, optional
        Mass, kg.
    g : float, optional
        Gravity, m/s², > 0 (the body falls down: a negative g would make it fall upward).
    rho : float, optional
        Air density, kg/m³.
    C_D : float, optional
        Drag coefficient (dimensionless).
    area : float, optional
        Frontal area, m².
    stop_at_ground : bool, optional
        Stop when x reaches 0 (a terminal ``solve_ivp`` event).
    t_eval : array_like, shape (N,), optional
        Times, s, at which to report the solution (default: the solver's own steps).

    Returns
    -------
    scipy.integrate OdeResult
        ``.t`` (s), ``.y`` shape (2, N) = position (m), velocity (m/s); ``.t_events[0]`` holds the ground-impact
        time when ``stop_at_ground``.
    """
    duration = validate.scalar(duration, "duration", True)
    m, g = validate.scalar(m, "m", True), validate.scalar(g, "g", True)
    c = (
        0.5
        * validate.scalar(rho, "rho", True)
        * validate.scalar(C_D, "C_D", True)
        * validate.scalar(area, "area", True)
        / m
    )

    def rhs(_t, y):
        return [y[1], -g - c * abs(y[1]) * y[1]]  # (000 §4.4.1 Q1: m dv/dt = -mg - ½ρC_D A|v|v)

    def ground(_t, y):
        return y[0]

    ground.terminal, ground.direction = True, -1
    if t_eval is not None:
        t_eval = validate.array(t_eval, "t_eval")
        t_eval = t_eval[t_eval <= duration]
    y0 = [validate.scalar(x0, "x0"), validate.scalar(v0, "v0")]
    events = ground if validate.flag(stop_at_ground, "stop_at_ground") else None
    return solve_ivp(rhs, (0.0, duration), y0, method="RK45", rtol=1e-10, atol=1e-10, t_eval=t_eval, events=events)


# ----------------------------------------------------------------------------------------------------------------
# Part B: state space (000 §4.4.2)
# ----------------------------------------------------------------------------------------------------------------


def falling_body_state_space(
    k: float = 0.25, m: float = 10.0, g: float = 9.8, dt: float = 0.01
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``A``, ``B``, ``u`` of the falling body so that ``x_t = A x_{t-1} + B u`` (000 §4.4.2 step c, §4.4.3 b).

    ``A = [[1, dt], [0, 1 - (k/m) dt]]``, ``B = [[1, 0], [0, -g dt]]``, ``u = [0, 1]``, so ``B u = [0, -g dt]``:
    the thesis puts gravity in B and a constant unit "input" in u.

    Parameters
    ----------
    k : float, optional
        Linear drag coefficient, kg/s.
    m : float, optional
        Mass, kg.
    g : float, optional
        Gravity, m/s², > 0 (the body falls down: a negative g would make it fall upward).
    dt : float, optional
        Time step, s.

    Returns
    -------
    A : ndarray, shape (2, 2)
        Transition matrix.
    B : ndarray, shape (2, 2)
        Input matrix.
    u : ndarray, shape (2,)
        Input vector.

    Examples
    --------
    >>> A, B, u = falling_body_state_space()
    >>> B @ u                                   # gravity enters as a velocity change of -g dt per step
    array([ 0.   , -0.098])
    """
    k, m = validate.scalar(k, "k", True), validate.scalar(m, "m", True)
    g, dt = validate.scalar(g, "g", True), validate.time_step(dt, "dt")
    A = np.array([[1.0, dt], [0.0, 1.0 - (k / m) * dt]])  # (000 §4.4.2)
    B = np.array([[1.0, 0.0], [0.0, -g * dt]])  # (000 §4.4.2)
    u = np.array([0.0, 1.0])  # (000 §4.4.2)
    return A, B, u


def mass_spring_damper_ss(
    m: float, b: float, k: float, input: str = "force"
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Continuous state space ``ẋ = A x + B u``, ``y = C x + D u`` of a mass-spring-damper (000 §4.4.2 question 1).

    State ``[x, ẋ]`` (displacement m, velocity m/s); output the displacement x. The thesis' figure is missing, so
    two readings are offered:

    * ``input='force'``: a force F (N) on the mass, ``m ẍ + b ẋ + k x = F`` →
      ``A = [[0, 1], [-k/m, -b/m]]``, ``B = [[0], [1/m]]``;
    * ``input='base_accel'``: the accelerometer proof mass of eq 3.2, ``ẍ + (b/m) ẋ + (k/m) x = -a(t)`` →
      the same A, ``B = [[0], [-1]]`` with u = a (m/s²).

    In both, ``C = [[1, 0]]`` and ``D = [[0]]``.

    Parameters
    ----------
    m : float
        Mass, kg.
    b : float
        Damping, N s/m, >= 0 (0: undamped).
    k : float
        Spring stiffness, N/m.
    input : {'force', 'base_accel'}, optional
        What drives the mass (see above).

    Returns
    -------
    A : ndarray, shape (2, 2)
        State matrix.
    B : ndarray, shape (2, 1)
        Input matrix.
    C : ndarray, shape (1, 2)
        Output matrix.
    D : ndarray, shape (1, 1)
        Feed-through matrix.
    """
    m, k = validate.scalar(m, "m", True), validate.scalar(k, "k", True)
    b = validate.scalar(b, "b")
    if b < 0:
        raise ValueError(f"b must be >= 0 (a damper takes energy out); got {b!r}")
    A = np.array([[0.0, 1.0], [-k / m, -b / m]])  # (000 eq 3.2 in state form)
    if input == "force":
        B = np.array([[0.0], [1.0 / m]])
    elif input == "base_accel":
        B = np.array([[0.0], [-1.0]])  # (000 eq 3.2: right-hand side -a(t))
    else:
        raise ValueError(f"input must be 'force' or 'base_accel'; got {input!r}")
    return A, B, np.array([[1.0, 0.0]]), np.zeros((1, 1))


# ----------------------------------------------------------------------------------------------------------------
# Part C: the filter (000 §4.3.1 and §4.4.3)
# ----------------------------------------------------------------------------------------------------------------


def seed000_labcode_kalman(
    x: ArrayLike, P: ArrayLike, z: ArrayLike, A: ArrayLike, Q: ArrayLike, H: ArrayLike, R: ArrayLike
) -> tuple[np.ndarray, np.ndarray]:
    """Thesis lab 2 Part C ``Kalman_Filter`` function, verbatim (000 §4.4.3 step c)::

        K = (s.P)*(s.H)'*inv((s.H)*(s.P)*(s.H)'+(s.R));
        s.x = (s.x) + K*((s.z)-(s.H)*(s.x));
        s.P = (s.P) - K*(s.H)*(s.P);
        s.P = (s.A)*(s.P)*(s.A)' + (s.Q);

    Erratum: the state projection ``s.x = s.A*s.x + s.B*s.u`` is missing, so the estimate is never moved forward
    between measurements; the covariance is projected as if it were. The short form replaces the Joseph form that
    the theory column shows (equal at this optimal K).

    Parameters
    ----------
    x : array_like, shape (n,)
        State (``s.x``).
    P : array_like, shape (n, n)
        Covariance (``s.P``).
    z : array_like, shape (m,)
        Measurement (``s.z``).
    A : array_like, shape (n, n)
        Transition matrix (``s.A``).
    Q : array_like, shape (n, n)
        Process noise covariance (``s.Q``).
    H : array_like, shape (m, n)
        Measurement matrix (``s.H``).
    R : array_like, shape (m, m)
        Measurement noise covariance (``s.R``).

    Returns
    -------
    x : ndarray, shape (n,)
        The updated (never projected) state.
    P : ndarray, shape (n, n)
        The updated and projected covariance.
    """
    d = kalman.check_model(x=x, P=P, z=z, A=A, Q=Q, H=H, R=R)
    x, P, z, A, Q, H, R = (d[k] for k in "x P z A Q H R".split())
    K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)  # (000 §4.4.3, printed code)
    x = x + K @ (z - H @ x)  # (000 §4.4.3, printed code)
    P = P - K @ H @ P  # (000 §4.4.3, printed code)
    P = A @ P @ A.T + Q  # (000 §4.4.3, printed code)
    return x, P


class ThesisKF:
    """The thesis' Kalman filter, one measurement at a time (000 §4.3.1 summary, fig 26; lab §4.4.3).

    Each :meth:`step` does what fig 26 draws, in its order: gain (4.31), update (4.8), covariance (4.17 or an
    alternate form), then the projection to the next step (4.32 with ``B u``, 4.36). The state it holds between
    steps is therefore the *prior* for the next measurement; :meth:`step` returns the *posterior* (the estimate of
    the state the measurement was taken at).

    Parameters
    ----------
    A : array_like, shape (n, n)
        Transition matrix (the lab's ``s.A``).
    B : array_like, shape (n, p)
        Input matrix (``s.B``).
    u : array_like, shape (p,)
        Input (``s.u``).
    Q : array_like, shape (n, n)
        Process noise covariance (``s.Q``).
    R : array_like, shape (m, m)
        Measurement noise covariance (``s.R``).
    H : array_like, shape (m, n)
        Measurement matrix (``s.H``).
    x0 : array_like, shape (n,)
        Initial estimate, ``x̂₀ = E(x)`` (the thesis prints "E(0)", see the lab's erratum). It is the
        prior for the *first measurement*. The lab passes ``[x0, v0]`` = ``tru(1)`` while its first measurement is
        of ``tru(2)``: a velocity offset of g·dt = 0.098 m/s that the filter removes within a few steps.
    P0 : array_like, shape (n, n)
        Its covariance.
    covariance : {'joseph', 'short', 'information'}, optional
        Form of the covariance update.
    project_state : bool, optional
        False reproduces the printed MATLAB code (no ``s.x = s.A*s.x + s.B*s.u``).
    control : bool, optional
        False reproduces eq 4.32 as printed (``x' = Φ x``, no ``G u``).

    Attributes
    ----------
    x : ndarray, shape (n,)
        The current prior state.
    P : ndarray, shape (n, n)
        The current prior covariance.
    x_post : ndarray, shape (n,) or None
        Posterior state of the last step.
    P_post : ndarray, shape (n, n) or None
        Posterior covariance of the last step.
    K : ndarray, shape (n, m) or None
        Gain of the last step.
    """

    def __init__(
        self,
        A: ArrayLike,
        B: ArrayLike,
        u: ArrayLike,
        Q: ArrayLike,
        R: ArrayLike,
        H: ArrayLike,
        x0: ArrayLike,
        P0: ArrayLike,
        covariance: str = "joseph",
        project_state: bool = True,
        control: bool = True,
    ) -> None:
        d = kalman.check_model(x=x0, P=P0, A=A, Q=Q, H=H, R=R, B=B, u=u, names={"x": "x0", "P": "P0"})
        self.A, self.B, self.u, self.Q, self.R, self.H = (d[k] for k in ("A", "B", "u", "Q", "R", "H"))
        self.x, self.P = d["x"].copy(), d["P"].copy()
        self.covariance = kalman.check_covariance_form(covariance)
        self.project_state = validate.flag(project_state, "project_state")
        self.control = validate.flag(control, "control")
        self.x_post = self.P_post = self.K = None

    @classmethod
    def falling_body(
        cls,
        x0: ArrayLike = (200.0, 0.0),
        P0: ArrayLike | None = None,
        mn_std: float = 12.0,
        pn_std: float = 0.4,
        k: float = 0.25,
        m: float = 10.0,
        g: float = 9.8,
        dt: float = 0.01,
        **options,
    ) -> ThesisKF:
        """The lab's filter (000 §4.4.3 step b): ``R = MNstd² I``, ``Q = PNstd² I``, ``H = I``, ``P0 = MNstd² I``.

        Parameters
        ----------
        x0 : array_like, shape (2,), optional
            Initial estimate ``[position (m), velocity (m/s)]``.
        P0 : array_like, shape (2, 2), optional
            Its covariance (default ``mn_std² I``).
        mn_std : float, optional
            Measurement noise std (the printed ``MNstd``), m and m/s.
        pn_std : float, optional
            Process noise std (the printed ``PNstd``), m and m/s.
        k : float, optional
            Linear drag coefficient, kg/s.
        m : float, optional
            Mass, kg.
        g : float, optional
            Gravity, m/s², > 0 (the body falls down: a negative g would make it fall upward).
        dt : float, optional
            Time step, s.
        **options
            ``covariance``, ``project_state``, ``control`` as in :class:`ThesisKF`.

        Returns
        -------
        ThesisKF
            The filter, ready for its first measurement.
        """
        A, B, u = falling_body_state_space(k, m, g, dt)
        mn_std, pn_std = validate.scalar(mn_std, "mn_std", True), validate.scalar(pn_std, "pn_std", True)
        P0 = mn_std**2 * np.eye(2) if P0 is None else P0
        return cls(A, B, u, pn_std**2 * np.eye(2), mn_std**2 * np.eye(2), np.eye(2), x0, P0, **options)

    def step(self, z: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """One measurement: update, then project.

        Parameters
        ----------
        z : array_like, shape (m,)
            The measurement.

        Returns
        -------
        x_post : ndarray, shape (n,)
            Posterior state.
        P_post : ndarray, shape (n, n)
            Posterior covariance.
        """
        z = validate.exact_shape(z, "z", (self.H.shape[0],))
        self.x_post, self.P_post, self.K = kalman.update_step(self.x, self.P, z, self.H, self.R, self.covariance)
        Bu = self.B @ self.u if self.control else None
        x_next, self.P = kalman.predict_step(self.x_post, self.P_post, self.A, self.Q, Bu)
        self.x = x_next if self.project_state else self.x_post  # printed code: s.x is never projected
        return self.x_post, self.P_post

    def run(self, zs: ArrayLike) -> dict[str, np.ndarray]:
        """Filter all measurements, one :meth:`step` each.

        Parameters
        ----------
        zs : array_like, shape (N, m)
            The measurements.

        Returns
        -------
        dict of ndarray
            ``x`` (N, n) and ``P`` (N, n, n) posteriors, ``x_prior`` (N, n) and ``P_prior`` (N, n, n) the state each
            step started from, ``K`` (N, n, m).
        """
        zs = validate.array(zs, "zs", shape=(None, self.H.shape[0]))
        if zs.ndim != 2:
            raise ValueError(f"zs must have shape (N, {self.H.shape[0]}); got {zs.shape}")
        n, m = self.H.shape[1], self.H.shape[0]
        out = {
            "x": np.empty((len(zs), n)),
            "P": np.empty((len(zs), n, n)),
            "x_prior": np.empty((len(zs), n)),
            "P_prior": np.empty((len(zs), n, n)),
            "K": np.empty((len(zs), n, m)),
        }
        for i, z in enumerate(zs):
            out["x_prior"][i], out["P_prior"][i] = self.x, self.P
            out["x"][i], out["P"][i] = self.step(z)
            out["K"][i] = self.K
        return out


def simulate_falling_body(
    n_runs: int,
    seed: int,
    n_steps: int = 199,
    first_run: int = 0,
    x0: float = 200.0,
    v0: float = 0.0,
    k: float = 0.25,
    m: float = 10.0,
    g: float = 9.8,
    dt: float = 0.01,
    pn_std: float = 0.4,
    mn_std: float = 12.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Truth and measurements of the lab's simulation loop (000 §4.4.3 step d), for many runs.

    Per step, as printed: ``tru(t) = A tru(t-1) + B u + PNstd·randn(2,1)`` then
    ``z = H tru(t) + MNstd·randn(2,1)`` with ``H = I``; ``tru(1) = [x0, v0]`` (the printed code never sets it).
    Run ``r`` draws from its own generator ``default_rng(SeedSequence(seed, spawn_key=(r,)))`` -- the r-th child
    of ``SeedSequence(seed)`` -- so a run is the same whatever batch it is simulated in.

    Parameters
    ----------
    n_runs : int
        Number of runs.
    seed : int
        The Monte-Carlo seed.
    n_steps : int, optional
        Measurements per run (199 as in the lab).
    first_run : int, optional
        Index of the first run (for batches).
    x0 : float, optional
        Start position, m.
    v0 : float, optional
        Start velocity, m/s.
    k : float, optional
        Linear drag coefficient, kg/s.
    m : float, optional
        Mass, kg.
    g : float, optional
        Gravity, m/s², > 0 (the body falls down: a negative g would make it fall upward).
    dt : float, optional
        Time step, s.
    pn_std : float, optional
        Process noise std, m and m/s per step.
    mn_std : float, optional
        Measurement noise std, m and m/s.

    Returns
    -------
    truth : ndarray, shape (n_runs, n_steps + 1, 2)
        ``[x (m), v (m/s)]``; index 0 is ``tru(1)``.
    z : ndarray, shape (n_runs, n_steps, 2)
        Measurements; ``z[:, i]`` measures ``truth[:, i + 1]``.
    """
    n_runs, n_steps = validate.count(n_runs, "n_runs", 1), validate.count(n_steps, "n_steps", 1)
    seed, first_run = validate.count(seed, "seed", 0), validate.count(first_run, "first_run", 0)
    A, B, u = falling_body_state_space(k, m, g, dt)
    pn_std, mn_std = (
        validate.scalar(pn_std, "pn_std", nonnegative=True),
        validate.scalar(mn_std, "mn_std", nonnegative=True),
    )
    noise = np.stack(
        [
            np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(r,))).standard_normal((n_steps, 4))
            for r in range(first_run, first_run + n_runs)
        ]
    )
    truth = np.empty((n_runs, n_steps + 1, 2))
    truth[:, 0] = validate.scalar(x0, "x0"), validate.scalar(v0, "v0")
    Bu = B @ u
    for i in range(n_steps):
        truth[:, i + 1] = truth[:, i] @ A.T + Bu + pn_std * noise[:, i, :2]  # (000 §4.4.3 d, eq 4.1)
    z = truth[:, 1:] + mn_std * noise[:, :, 2:]  # (000 §4.4.3 d, eq 4.3, H = I)
    return truth, z


def monte_carlo(
    n_runs: int = 200,
    seed: int = 2,
    batch: int = 50,
    variants: dict | None = None,
    progress: bool = True,
    n_steps: int = 199,
    **model: float,
) -> dict:
    """Seeded Monte Carlo of the lab's filter variants on the same simulated falling bodies (000 §4.4.3).

    Runs are simulated with :func:`simulate_falling_body` in batches of ``batch`` (run r is the same whatever the
    batch size) and filtered with :func:`fusionlab.kalman.kf_batch`; a tqdm bar counts runs.

    Parameters
    ----------
    n_runs : int, optional
        Number of runs.
    seed : int, optional
        The Monte-Carlo seed.
    batch : int, optional
        Runs simulated and filtered together.
    variants : dict, optional
        Name -> dict of :func:`fusionlab.kalman.kf_batch` options (``covariance``, ``project_state``,
        ``control``, ``x0``, ``P0``, ``Q``, ``R``), or None for the lab's two: ``'thesis filter'`` (with the
        state projection) and ``'printed code'`` (without it, short form).
    progress : bool, optional
        Show the tqdm bar.
    n_steps : int, optional
        Measurements per run.
    **model
        Passed to :func:`simulate_falling_body` (``x0``, ``v0``, ``k``, ``m``, ``g``, ``dt``, ``pn_std``,
        ``mn_std``); the filters use the same values unless a variant overrides them.

    Returns
    -------
    dict
        ``'n_runs'``, ``'seed'``, ``'meas_rms'`` (2,) position (m) and velocity (m/s) RMS of the measurements, and
        ``'variants'``: name -> dict with ``'rms'`` (2,), ``'rms_t'`` (N, 2) RMS over runs at each step,
        ``'mean_err_t'`` (N, 2), ``'nees_t'`` (N,) mean NEES over runs, ``'P'`` (N, 2, 2).
    """
    from tqdm.auto import tqdm

    n_runs, batch = validate.count(n_runs, "n_runs", 1), validate.count(batch, "batch", 1)
    n_steps, seed = validate.count(n_steps, "n_steps", 1), validate.count(seed, "seed", 0)
    validate.options(model, [k_ for k_ in LAB2 if k_ != "tmax"], "monte_carlo")
    model = {
        k_: validate.scalar(v, k_, positive=k_ in ("k", "m", "dt", "mn_std"), nonnegative=k_ == "pn_std")
        for k_, v in model.items()
    }
    p = dict(LAB2)
    p.update(model)
    A, B, u = falling_body_state_space(p["k"], p["m"], p["g"], p["dt"])
    base = dict(
        A=A,
        B=B,
        u=u,
        Q=p["pn_std"] ** 2 * np.eye(2),
        R=p["mn_std"] ** 2 * np.eye(2),
        H=np.eye(2),
        x0=np.array([p["x0"], p["v0"]]),
        P0=p["mn_std"] ** 2 * np.eye(2),
    )
    if variants is None:
        variants = {"thesis filter": {}, "printed code": {"project_state": False, "covariance": "short"}}
    if not isinstance(variants, dict) or not variants:
        raise ValueError(f"variants must be a non-empty dict name -> kf_batch options; got {variants!r}")
    for name, opts in variants.items():
        validate.options(
            opts, ("covariance", "project_state", "control", "x0", "P0", "Q", "R"), f"monte_carlo variant {name!r}"
        )
    sims = {k_: p[k_] for k_ in ("x0", "v0", "k", "m", "g", "dt", "pn_std", "mn_std")}
    sq_meas = np.zeros(2)
    acc = {
        name: {"sq": np.zeros((n_steps, 2)), "err": np.zeros((n_steps, 2)), "nees": np.zeros(n_steps)}
        for name in variants
    }
    P_of = {}
    with tqdm(total=n_runs, desc="Monte Carlo", unit="run", disable=not progress) as bar:
        for start in range(0, n_runs, batch):
            nb = min(batch, n_runs - start)
            truth, z = simulate_falling_body(nb, seed, n_steps=n_steps, first_run=start, **sims)
            sq_meas += ((z - truth[:, 1:]) ** 2).sum(axis=(0, 1))
            for name, opts in variants.items():
                res = kalman.kf_batch(z, **{**base, **opts})
                e = res["x"] - truth[:, 1:]
                acc[name]["sq"] += (e**2).sum(axis=0)
                acc[name]["err"] += e.sum(axis=0)
                acc[name]["nees"] += kalman.nees(e, res["P"][None]).sum(axis=0)
                P_of[name] = res["P"]
            bar.update(nb)
    out = {"n_runs": n_runs, "seed": seed, "meas_rms": np.sqrt(sq_meas / (n_runs * n_steps)), "variants": {}}
    for name, a in acc.items():
        out["variants"][name] = {
            "rms": np.sqrt(a["sq"].sum(axis=0) / (n_runs * n_steps)),
            "rms_t": np.sqrt(a["sq"] / n_runs),
            "mean_err_t": a["err"] / n_runs,
            "nees_t": a["nees"] / n_runs,
            "P": P_of[name],
        }
    return out
