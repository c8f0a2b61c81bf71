"""The Kalman filter from first principles, and the falling body of thesis lab 2 (seed 000 §4.2-4.4).

What is here, in the order the lab uses it
-------------------------------------------
* **Foundations** (000 §4.2-4.3): the product of two Gaussians (figs 24-25), the scalar recursive least-squares
  estimator (eq 4.8), the gain (4.31), the three covariance updates -- Joseph form (4.17), short form
  ``(I - KH)P`` and information form ``(P⁻¹ + HᵀR⁻¹H)⁻¹`` (summary 4.37) -- the gradient of ``tr P`` (4.29/4.30)
  and the printed, mis-ordered expansion (4.27) kept for the erratum.
* **Part A** (000 §4.4.1): the linear-drag falling body ``dv/dt = -(k/m) v - g``, Euler-discretised exactly as the
  lab prints it (:func:`seed000_labcode_falling_body`, including its 199-step loop), the fixed version on a time
  axis, the closed form, terminal velocity and time constant, and quadratic drag with ``scipy.integrate.solve_ivp``.
* **Part B** (000 §4.4.2): the state-space matrices ``A``, ``B`` and input ``u``; the mass-spring-damper question.
* **Part C** (000 §4.4.3): :class:`ThesisKF` -- the thesis' update-then-project loop (fig 26), written line by line
  from the equations, with switches for the printed MATLAB code (no state projection, short form) and for eq 4.32
  as printed (no control term); :func:`kf_batch`, the same filter vectorised over Monte-Carlo runs;
  :func:`simulate_falling_body`, :func:`monte_carlo` (seeded, batched, with a progress bar), the steady state
  from the discrete algebraic Riccati equation and the NEES consistency statistic.

Conventions
-----------
State ``x`` is ``[position (m, up), velocity (m/s, up)]`` for the falling body; in general ``x`` has shape ``(n,)``,
``P`` ``(n, n)``, ``H`` ``(m, n)``, ``R`` ``(m, m)``, ``z`` ``(m,)``, ``A`` ``(n, n)``, ``B`` ``(n, p)``,
``u`` ``(p,)``. The thesis writes the transition matrix as F, Φ or A and the input matrix as G or B; here it is
``A`` and ``B`` as in its lab code. The thesis' loop order is *update, then project*: the state a step starts with
is the prior for the measurement it receives. Gravity in lab 2 is the thesis' ``g = 9.8`` m/s².

Everything numeric in the lab that the seed does not print (the closed form, NEES, the DARE steady state, the
drag constants) is labelled as an addition in its docstring.
"""
from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp
from scipy.linalg import solve_discrete_are
from scipy.stats import chi2

from . import validate

__all__ = [
    "LAB2", "AIR_DENSITY", "SPHERE_CD", "SPHERE_AREA", "terminal_velocity", "time_constant", "seed000_labcode_falling_body", "falling_body_euler",
    "falling_body_exact", "quadratic_terminal_velocity", "falling_body_quadratic",
    "falling_body_state_space", "mass_spring_damper_ss",
    "gaussian_product", "rls_scalar", "kalman_gain", "joseph_covariance", "short_covariance",
    "information_covariance", "gain_from_posterior", "expanded_covariance", "seed000_eq427_printed",
    "trace_gradient", "update", "predict", "seed000_labcode_kalman", "ThesisKF", "kf_batch",
    "simulate_falling_body", "monte_carlo", "steady_state", "nees", "nees_bounds",
]

#: Thesis lab 2 parameters (000 §4.4.1 and §4.4.3), SI units. ``tmax`` is the printed ``TMAX`` (a count of
#: array slots, not seconds); ``mn_std``/``pn_std`` are the printed ``MNstd``/``PNstd``.
LAB2 = dict(k=0.25, m=10.0, g=9.8, dt=0.01, tmax=200, x0=200.0, v0=0.0, mn_std=12.0, pn_std=0.4)

#: Quadratic-drag constants assumed for Part A's question (the thesis gives none): sea-level air, a smooth sphere
#: 25 cm across (C_D of a sphere at these Reynolds numbers), mass 10 kg as in the lab.
AIR_DENSITY = 1.225          # kg/m^3, ISA sea level
SPHERE_CD = 0.47             # -, smooth sphere, Re ~ 1e5
SPHERE_AREA = np.pi * 0.125 ** 2   # m^2, frontal area of a 0.25 m sphere


# ----------------------------------------------------------------------------------------------------------------
# Input checking (once, at the public door)
# ----------------------------------------------------------------------------------------------------------------

def _exact(a, name, shape):
    """``a`` as a float array of exactly ``shape``; ValueError naming ``name`` otherwise."""
    a = validate.array(a, name)
    if a.shape != tuple(shape):
        raise ValueError(f"{name} must have shape {tuple(shape)}; got {a.shape}")
    return a


def _square(a, name):
    a = validate.array(a, name)
    if a.ndim != 2 or a.shape[0] != a.shape[1]:
        raise ValueError(f"{name} must be a square matrix (n, n); got shape {a.shape}")
    return a


def _scalar(x, name, positive=False):
    a = validate.array(x, name)
    if a.ndim != 0:
        raise ValueError(f"{name} must be a single number; got shape {a.shape}")
    if positive and not a > 0:
        raise ValueError(f"{name} must be > 0; got {float(a)!r}")
    return float(a)


def _count(x, name, minimum=1):
    return validate.count(x, name, minimum)


_KEYS = ("P", "H", "R", "A", "Q", "B", "u", "x", "z", "K")


def _model(names=None, optional=(), **given):
    """Check a set of Kalman-filter matrices against each other; returns them as arrays in a dict.

    ``given`` uses the canonical names ``P H R A Q B u x z K``; ``names`` maps them to the caller's argument names
    (``{'P': 'P0'}``) so that a message names what the caller typed. Every given key is required (None is an
    error naming it) unless listed in ``optional``. P, R and Q are checked as covariances (symmetric, positive
    semi-definite).
    """
    nm = {k: k for k in _KEYS}
    nm.update(names or {})
    for key, val in given.items():
        if val is None and key not in optional:
            raise ValueError(f"{nm[key]} is required (an array); got None")
    P, H, R, A, Q, B, u, x, z, K = (given.get(k) for k in _KEYS)
    n = m = None
    if P is not None:
        P = validate.covariance(P, nm["P"])
        n = P.shape[0]
    if A is not None:
        A = _square(A, nm["A"])
        if n is not None and A.shape != (n, n):
            raise ValueError(f"{nm['A']} must have shape ({n}, {n}) to match {nm['P']}; got {A.shape}")
        n = A.shape[0]
    if x is not None:
        x = validate.array(x, nm["x"])
        if n is None:
            n = x.shape[0] if x.ndim == 1 else None
        if x.shape != (n,):
            raise ValueError(f"{nm['x']} must have shape ({n},); got {x.shape}")
    if H is not None:
        H = validate.array(H, nm["H"])
        if H.ndim != 2 or (n is not None and H.shape[1] != n):
            raise ValueError(f"{nm['H']} must have shape (m, {n}); got {H.shape}")
        m = H.shape[0]
    if R is not None:
        R = validate.covariance(R, nm["R"])
        if m is not None and R.shape != (m, m):
            raise ValueError(f"{nm['R']} must have shape ({m}, {m}) to match {nm['H']}; got {R.shape}")
        m = R.shape[0]
    if Q is not None:
        Q = validate.covariance(Q, nm["Q"], n=n)
    if z is not None:
        z = _exact(z, nm["z"], (m,))
    if K is not None:
        K = validate.array(K, nm["K"])
        if K.shape != (n, m):
            raise ValueError(f"{nm['K']} must have shape ({n}, {m}) to match {nm['P']} and {nm['H']} (n = {n} "
                             f"states, m = {m} measurements); got {K.shape}")
    if B is not None or u is not None:
        if B is None or u is None:
            raise ValueError(f"{nm['B']} and {nm['u']} must be given together (the control term is B @ u)")
        B = validate.array(B, nm["B"])
        if B.ndim != 2 or B.shape[0] != n:
            raise ValueError(f"{nm['B']} must have shape ({n}, p); got {B.shape}")
        u = validate.array(u, nm["u"])
        if u.shape != (B.shape[1],):
            raise ValueError(f"{nm['u']} must have shape ({B.shape[1]},) to match {nm['B']} {B.shape}; "
                             f"got {u.shape}")
    return dict(P=P, H=H, R=R, A=A, Q=Q, B=B, u=u, x=x, z=z, K=K)


# ----------------------------------------------------------------------------------------------------------------
# Part A: the falling body (000 §4.4.1)
# ----------------------------------------------------------------------------------------------------------------

def terminal_velocity(k, m, g=9.8):
    """Terminal velocity of the linear-drag model, m/s: set ``dv/dt = -(k/m) v - g = 0`` (000 §4.4.1).

    Parameters
    ----------
    k : float
        Linear drag coefficient, kg/s (> 0).
    m : float
        Mass, kg (> 0).
    g : float, optional
        Gravity, m/s².

    Returns
    -------
    float
        ``-m g / k`` in m/s (negative: downwards). Lab values: -392 m/s.

    Examples
    --------
    >>> terminal_velocity(0.25, 10.0)
    -392.0
    """
    k, m, g = _scalar(k, "k", True), _scalar(m, "m", True), _scalar(g, "g")
    return -m * g / k


def time_constant(k, m):
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
    return _scalar(m, "m", True) / _scalar(k, "k", True)


def seed000_labcode_falling_body(k=0.25, m=10.0, g=9.8, dt=0.01, TMAX=200, x0=200.0, v0=0.0):
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
        Gravity, m/s².
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
    k, m, g = _scalar(k, "k", True), _scalar(m, "m", True), _scalar(g, "g")
    dt, x0, v0 = _scalar(dt, "dt", True), _scalar(x0, "x0"), _scalar(v0, "v0")
    TMAX = _count(TMAX, "TMAX")
    X = np.zeros(TMAX)
    V = np.zeros(TMAX)
    X[0], V[0] = x0, v0
    for t in range(1, TMAX):                                        # MATLAB: for t=2:TMAX
        X[t] = X[t - 1] + (V[t - 1]) * dt                            # (000 §4.4.1, x_t = x_{t-1} + v_{t-1} dt)
        V[t] = V[t - 1] + (-(k / m) * (V[t - 1]) - g) * dt           # (000 §4.4.1, v_t = v_{t-1} - (k/m v + g) dt)
    return X, V


def falling_body_euler(duration, k=0.25, m=10.0, g=9.8, dt=0.01, x0=200.0, v0=0.0):
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
        Gravity, m/s².
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
    duration, dt = _scalar(duration, "duration", True), _scalar(dt, "dt", True)
    k, m, g = _scalar(k, "k", True), _scalar(m, "m", True), _scalar(g, "g")
    n = int(round(duration / dt))
    if abs(n * dt - duration) > 1e-9 * max(1.0, duration):
        raise ValueError(f"duration must be a whole number of steps dt = {dt:g} s; got {duration:g} s")
    out = np.empty((n + 1, 2))
    out[0] = _scalar(x0, "x0"), _scalar(v0, "v0")
    for i in range(n):
        x, v = out[i]
        out[i + 1, 0] = x + v * dt                                   # (000 §4.4.1)
        out[i + 1, 1] = v + (-(k / m) * v - g) * dt                  # (000 §4.4.1)
    return np.arange(n + 1) * dt, out


def falling_body_exact(t, k=0.25, m=10.0, g=9.8, x0=200.0, v0=0.0):
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
        Gravity, m/s².
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
    x0, v0 = _scalar(x0, "x0"), _scalar(v0, "v0")
    decay = np.exp(-t / tau)
    v = vT + (v0 - vT) * decay
    x = x0 + vT * t + (v0 - vT) * tau * (1 - decay)
    return np.stack([x, v], -1)


def quadratic_terminal_velocity(m=10.0, g=9.8, rho=AIR_DENSITY, C_D=SPHERE_CD, area=SPHERE_AREA):
    """Terminal velocity with quadratic drag ``D = ½ ρ C_D A v²`` (000 §4.4.1 question 1), m/s, negative (down).

    ``m g = ½ ρ C_D A v_T²`` gives ``v_T = -sqrt(2 m g / (ρ C_D A))``. With the module's assumed constants
    (10 kg sphere, 25 cm across, sea-level air): -83.3 m/s.

    Parameters
    ----------
    m : float, optional
        Mass, kg.
    g : float, optional
        Gravity, m/s².
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
    m, g = _scalar(m, "m", True), _scalar(g, "g", True)
    rho, C_D, area = _scalar(rho, "rho", True), _scalar(C_D, "C_D", True), _scalar(area, "area", True)
    return -np.sqrt(2 * m * g / (rho * C_D * area))


def falling_body_quadratic(duration, x0=200.0, v0=0.0, m=10.0, g=9.8, rho=AIR_DENSITY, C_D=SPHERE_CD,
                           area=SPHERE_AREA, stop_at_ground=True, t_eval=None):
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
        Gravity, m/s².
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
    duration = _scalar(duration, "duration", True)
    m, g = _scalar(m, "m", True), _scalar(g, "g")
    c = 0.5 * _scalar(rho, "rho", True) * _scalar(C_D, "C_D", True) * _scalar(area, "area", True) / m

    def rhs(_t, y):
        return [y[1], -g - c * abs(y[1]) * y[1]]                     # (000 §4.4.1 Q1: m dv/dt = -mg - ½ρC_D A|v|v)

    def ground(_t, y):
        return y[0]
    ground.terminal, ground.direction = True, -1
    if t_eval is not None:
        t_eval = validate.array(t_eval, "t_eval")
        t_eval = t_eval[t_eval <= duration]
    return solve_ivp(rhs, (0.0, duration), [_scalar(x0, "x0"), _scalar(v0, "v0")], method="RK45",
                     rtol=1e-10, atol=1e-10, t_eval=t_eval, events=ground if stop_at_ground else None)


# ----------------------------------------------------------------------------------------------------------------
# Part B: state space (000 §4.4.2)
# ----------------------------------------------------------------------------------------------------------------

def falling_body_state_space(k=0.25, m=10.0, g=9.8, dt=0.01):
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
        Gravity, m/s².
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
    k, m, g, dt = _scalar(k, "k", True), _scalar(m, "m", True), _scalar(g, "g"), _scalar(dt, "dt", True)
    A = np.array([[1.0, dt], [0.0, 1.0 - (k / m) * dt]])            # (000 §4.4.2)
    B = np.array([[1.0, 0.0], [0.0, -g * dt]])                       # (000 §4.4.2)
    u = np.array([0.0, 1.0])                                         # (000 §4.4.2)
    return A, B, u


def mass_spring_damper_ss(m, b, k, input="force"):
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
        Damping, N s/m.
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
    m, k = _scalar(m, "m", True), _scalar(k, "k", True)
    b = _scalar(b, "b")
    if b < 0:
        raise ValueError(f"b must be >= 0 (a damper takes energy out); got {b!r}")
    A = np.array([[0.0, 1.0], [-k / m, -b / m]])                     # (000 eq 3.2 in state form)
    if input == "force":
        B = np.array([[0.0], [1.0 / m]])
    elif input == "base_accel":
        B = np.array([[0.0], [-1.0]])                                # (000 eq 3.2: right-hand side -a(t))
    else:
        raise ValueError(f"input must be 'force' or 'base_accel'; got {input!r}")
    return A, B, np.array([[1.0, 0.0]]), np.zeros((1, 1))


# ----------------------------------------------------------------------------------------------------------------
# Foundations (000 §4.2-4.3)
# ----------------------------------------------------------------------------------------------------------------

def gaussian_product(mu1, var1, mu2, var2):
    """Mean and variance of the (normalised) product of two 1-D Gaussians (000 §4.2, figs 24-25).

    ``μ = (σ₂² μ₁ + σ₁² μ₂) / (σ₁² + σ₂²)``, ``σ² = σ₁² σ₂² / (σ₁² + σ₂²)``: the prediction N(μ₁, σ₁²) times the
    measurement N(μ₂, σ₂²). It is the scalar Kalman update with ``K = σ₁² / (σ₁² + σ₂²)``. (The thesis shows only
    the figures; the formulas are the standard ones.) Arrays broadcast.

    Parameters
    ----------
    mu1 : float or array_like
        Mean of the first Gaussian (the prediction), in the unit of the quantity.
    var1 : float or array_like
        Its variance, unit squared (> 0).
    mu2 : float or array_like
        Mean of the second Gaussian (the measurement).
    var2 : float or array_like
        Its variance (> 0).

    Returns
    -------
    mu : float or ndarray
        Mean of the product, of the broadcast shape.
    var : float or ndarray
        Its variance, always smaller than both ``var1`` and ``var2``.

    Examples
    --------
    A prediction of 10 ± 2 and a measurement of 12 ± 1: the product leans to the better one.

    >>> mu, var = gaussian_product(10.0, 4.0, 12.0, 1.0)
    >>> round(float(mu), 3), round(float(var), 3)
    (11.6, 0.8)
    """
    mu1, mu2 = validate.array(mu1, "mu1"), validate.array(mu2, "mu2")
    var1, var2 = validate.array(var1, "var1"), validate.array(var2, "var2")
    validate.broadcast(mu1=mu1, var1=var1, mu2=mu2, var2=var2)
    for v, name in ((var1, "var1"), (var2, "var2")):
        if np.any(v <= 0):
            raise ValueError(f"{name} must be > 0 (a variance); got min {float(np.min(v))!r}")
    mu = (var2 * mu1 + var1 * mu2) / (var1 + var2)                   # (000 §4.2, fig 25)
    var = var1 * var2 / (var1 + var2)
    return (float(mu), float(var)) if np.ndim(mu) == 0 else (mu, var)


def rls_scalar(y, R, x0=0.0, P0=np.inf):
    """Scalar recursive least squares for a constant (000 eqs 4.7, 4.8, 4.31, 4.17 with H = 1).

    ``K_k = P_{k-1} / (P_{k-1} + R)``, ``x̂_k = x̂_{k-1} + K_k (y_k - x̂_{k-1})``, ``P_k = (1 - K_k) P_{k-1}``.
    With ``P0 = inf`` (no prior knowledge, as the thesis' summary allows) the first gain is 1 and ``x̂_k`` is
    exactly the running mean of ``y_1..y_k``, with ``P_k = R / k``.

    Parameters
    ----------
    y : array_like, shape (N,)
        Measurements of the constant.
    R : float
        Measurement variance (> 0), unit of ``y`` squared.
    x0 : float, optional
        Initial estimate.
    P0 : float, optional
        Its variance (> 0, or inf for no prior knowledge).

    Returns
    -------
    x_hat : ndarray, shape (N,)
        Estimate after each measurement.
    P : ndarray, shape (N,)
        Its variance.
    K : ndarray, shape (N,)
        The gain used at each measurement.

    Examples
    --------
    With no prior the estimate is the running mean and ``P_k = R / k``:

    >>> x_hat, P, K = rls_scalar([1.0, 3.0, 2.0], R=1.0)
    >>> x_hat, np.round(P, 3)
    (array([1., 2., 2.]), array([1.   , 0.5  , 0.333]))
    """
    y = validate.array(y, "y")
    if y.ndim != 1:
        raise ValueError(f"y must have shape (N,); got {y.shape}")
    R = _scalar(R, "R", True)
    x = _scalar(x0, "x0")
    try:
        P = float(P0)
    except (TypeError, ValueError):
        raise ValueError(f"P0 must be a positive number or inf; got {P0!r}") from None
    if not P > 0:
        raise ValueError(f"P0 must be > 0 (use np.inf for no prior knowledge); got {P0!r}")
    x_hat, Ps, Ks = np.empty(len(y)), np.empty(len(y)), np.empty(len(y))
    for i, yk in enumerate(y):
        K = 1.0 if np.isinf(P) else P / (P + R)                      # (000 eq 4.31, H = 1)
        x = x + K * (yk - x)                                         # (000 eq 4.8)
        P = R if np.isinf(P) else (1 - K) ** 2 * P + K ** 2 * R      # (000 eq 4.17, H = 1)
        x_hat[i], Ps[i], Ks[i] = x, P, K
    return x_hat, Ps, Ks


def _gain(P, H, R):
    return P @ H.T @ np.linalg.inv(H @ P @ H.T + R)                  # (000 eq 4.31)


def _joseph(P, K, H, R):
    I_KH = np.eye(P.shape[0]) - K @ H
    return I_KH @ P @ I_KH.T + K @ R @ K.T                           # (000 eq 4.17)


def kalman_gain(P, H, R):
    """Optimal gain ``K = P Hᵀ (H P Hᵀ + R)⁻¹`` (000 eq 4.31), from the prior covariance ``P``.

    Parameters
    ----------
    P : array_like, shape (n, n)
        Prior covariance.
    H : array_like, shape (m, n)
        Measurement matrix.
    R : array_like, shape (m, m)
        Measurement noise covariance.

    Returns
    -------
    ndarray, shape (n, m)
        The gain ``K``.

    Examples
    --------
    >>> kalman_gain([[4.0]], [[1.0]], [[1.0]])
    array([[0.8]])
    """
    d = _model(P=P, H=H, R=R)
    return _gain(d["P"], d["H"], d["R"])


def joseph_covariance(P, K, H, R):
    """Posterior covariance, Joseph form ``(I - K H) P (I - K H)ᵀ + K R Kᵀ`` (000 eq 4.17).

    Valid for *any* gain K (it is the covariance of ``x - x̂`` for the estimator 4.8 with that K) and symmetric
    positive semi-definite by construction.

    Parameters
    ----------
    P : array_like, shape (n, n)
        Prior covariance.
    K : array_like, shape (n, m)
        Gain.
    H : array_like, shape (m, n)
        Measurement matrix.
    R : array_like, shape (m, m)
        Measurement noise covariance.

    Returns
    -------
    ndarray, shape (n, n)
        Posterior covariance.
    """
    d = _model(P=P, H=H, R=R, K=K)
    return _joseph(d["P"], d["K"], d["H"], d["R"])


def short_covariance(P, K, H):
    """Posterior covariance, short form ``(I - K H) P`` (000 §4.3.1 alternate form).

    The lab code's ``s.P = s.P - K*s.H*s.P``. Equals the Joseph form only at the optimal K.

    Parameters
    ----------
    P : array_like, shape (n, n)
        Prior covariance.
    K : array_like, shape (n, m)
        Gain.
    H : array_like, shape (m, n)
        Measurement matrix.

    Returns
    -------
    ndarray, shape (n, n)
        Posterior covariance.
    """
    d = _model(P=P, H=H, K=K)
    P, K, H = d["P"], d["K"], d["H"]
    return (np.eye(P.shape[0]) - K @ H) @ P                          # (000 §4.3.1, alternate form)


def information_covariance(P, H, R):
    """Posterior covariance, information form ``(P⁻¹ + Hᵀ R⁻¹ H)⁻¹`` (000 §4.3.1 alternate form).

    Parameters
    ----------
    P : array_like, shape (n, n)
        Prior covariance.
    H : array_like, shape (m, n)
        Measurement matrix.
    R : array_like, shape (m, m)
        Measurement noise covariance.

    Returns
    -------
    ndarray, shape (n, n)
        Posterior covariance.
    """
    d = _model(P=P, H=H, R=R)
    P, H, R = d["P"], d["H"], d["R"]
    return np.linalg.inv(np.linalg.inv(P) + H.T @ np.linalg.inv(R) @ H)   # (000 §4.3.1, alternate form)


def gain_from_posterior(P_post, H, R):
    """The alternate gain ``K = P_k Hᵀ R⁻¹`` (000 §4.3.1), written with the *posterior* covariance ``P_k``.

    Parameters
    ----------
    P_post : array_like, shape (n, n)
        Posterior covariance ``P_k``.
    H : array_like, shape (m, n)
        Measurement matrix.
    R : array_like, shape (m, m)
        Measurement noise covariance.

    Returns
    -------
    ndarray, shape (n, m)
        The gain.
    """
    d = _model(P=P_post, H=H, R=R, names={"P": "P_post"})
    return d["P"] @ d["H"].T @ np.linalg.inv(d["R"])                 # (000 §4.3.1, alternate form)


def expanded_covariance(P, K, H, R):
    """Eq 4.27 corrected: ``P - K H P - P Hᵀ Kᵀ + K (H P Hᵀ + R) Kᵀ``, the Joseph form multiplied out.

    Parameters
    ----------
    P : array_like, shape (n, n)
        Prior covariance.
    K : array_like, shape (n, m)
        Gain.
    H : array_like, shape (m, n)
        Measurement matrix.
    R : array_like, shape (m, m)
        Measurement noise covariance.

    Returns
    -------
    ndarray, shape (n, n)
        Posterior covariance.
    """
    d = _model(P=P, H=H, R=R, K=K)
    P, K, H, R = d["P"], d["K"], d["H"], d["R"]
    return P - K @ H @ P - P @ H.T @ K.T + K @ (H @ P @ H.T + R) @ K.T    # (000 eq 4.27, corrected)


def seed000_eq427_printed(P, K, H, R):
    """Seed 000 eq 4.27 *as printed*: ``P - P K H - P Kᵀ Hᵀ + K H P Kᵀ Hᵀ + K R Kᵀ``.

    Erratum: the factors are in the wrong order (the correct expansion is :func:`expanded_covariance`). The printed
    terms are not even defined unless H is square; with H = I and R = r·I (the lab's case) K commutes with P and
    the slip is invisible, which is why the lab shows it with a general H.

    Parameters
    ----------
    P : array_like, shape (n, n)
        Prior covariance.
    K : array_like, shape (n, m)
        Gain.
    H : array_like, shape (m, n)
        Measurement matrix.
    R : array_like, shape (m, m)
        Measurement noise covariance.

    Returns
    -------
    ndarray, shape (n, n)
        The printed expression's value (wrong in general).
    """
    d = _model(P=P, H=H, R=R, K=K)
    P, K, H, R = d["P"], d["K"], d["H"], d["R"]
    if H.shape[0] != H.shape[1]:
        raise ValueError(f"H must be square for the printed eq 4.27 to be defined (P Kᵀ Hᵀ); got {H.shape}")
    return P - P @ K @ H - P @ K.T @ H.T + K @ H @ P @ K.T @ H.T + K @ R @ K.T   # (000 eq 4.27, as printed)


def trace_gradient(P, K, H, R):
    """``∂ tr P_k / ∂K = -2 P Hᵀ + 2 K (H P Hᵀ + R)`` (000 eq 4.29 last line, = 4.30); zero at the optimal K.

    Parameters
    ----------
    P : array_like, shape (n, n)
        Prior covariance.
    K : array_like, shape (n, m)
        Gain.
    H : array_like, shape (m, n)
        Measurement matrix.
    R : array_like, shape (m, m)
        Measurement noise covariance.

    Returns
    -------
    ndarray, shape (n, m)
        The gradient of the trace of the posterior covariance with respect to ``K``.
    """
    d = _model(P=P, H=H, R=R, K=K)
    P, K, H, R = d["P"], d["K"], d["H"], d["R"]
    return -2 * P @ H.T + 2 * K @ (H @ P @ H.T + R)                  # (000 eq 4.30)


_FORMS = ("joseph", "short", "information")


def _check_form(form):
    if form not in _FORMS:
        raise ValueError(f"covariance must be one of {_FORMS}; got {form!r}")
    return form


def _update(x, P, z, H, R, form):
    K = _gain(P, H, R)                                               # (000 eq 4.31)
    x = x + K @ (z - H @ x)                                          # (000 eq 4.8)
    if form == "joseph":
        P = _joseph(P, K, H, R)                                      # (000 eq 4.17)
    elif form == "short":
        P = (np.eye(P.shape[0]) - K @ H) @ P                         # (000 §4.3.1 alternate form)
    else:
        P = np.linalg.inv(np.linalg.inv(P) + H.T @ np.linalg.inv(R) @ H)   # (000 §4.3.1 alternate form)
    return x, P, K


def update(x, P, z, H, R, covariance="joseph"):
    """Measurement update of the thesis' filter (000 eqs 4.31, 4.8, 4.17; fig 26 boxes 1-3).

    Parameters
    ----------
    x : array_like, shape (n,)
        Prior state.
    P : array_like, shape (n, n)
        Prior covariance.
    z : array_like, shape (m,)
        Measurement.
    H : array_like, shape (m, n)
        Measurement matrix.
    R : array_like, shape (m, m)
        Measurement noise covariance.
    covariance : {'joseph', 'short', 'information'}, optional
        Which form of the covariance update (all three agree at the optimal gain; Joseph is the one printed in the
        theory and the one filterpy uses).

    Returns
    -------
    x_post : ndarray, shape (n,)
        Posterior state.
    P_post : ndarray, shape (n, n)
        Posterior covariance.
    K : ndarray, shape (n, m)
        The gain used.

    See Also
    --------
    predict : the projection that follows.

    Examples
    --------
    One update of a 1-D filter: prior 0 with variance 4, measurement 1 with variance 1.

    >>> x, P, K = update([0.0], [[4.0]], [1.0], H=[[1.0]], R=[[1.0]])
    >>> np.round(x, 3), np.round(P, 3), np.round(K, 3)
    (array([0.8]), array([[0.8]]), array([[0.8]]))
    """
    d = _model(x=x, P=P, z=z, H=H, R=R)
    return _update(d["x"], d["P"], d["z"], d["H"], d["R"], _check_form(covariance))


def _predict(x, P, A, Q, Bu):
    x = A @ x if Bu is None else A @ x + Bu                          # (000 eq 4.32, with G u restored; eq 4.1)
    P = A @ P @ A.T + Q                                              # (000 eq 4.36)
    return x, P


def predict(x, P, A, Q, B=None, u=None):
    """State projection of the thesis' filter (000 eqs 4.32 and 4.36; fig 26 box 4).

    ``x' = A x + B u`` and ``P' = A P Aᵀ + Q``. Eq 4.32 prints ``x' = F x`` without the input term G u of
    its own model (4.1); the falling body needs it (gravity enters through B u). Leave ``B`` and ``u`` out to get
    4.32 as printed.

    Parameters
    ----------
    x : array_like, shape (n,)
        Posterior state.
    P : array_like, shape (n, n)
        Posterior covariance.
    A : array_like, shape (n, n)
        Transition matrix.
    Q : array_like, shape (n, n)
        Process noise covariance.
    B : array_like, shape (n, p), optional
        Input matrix; give it with ``u`` or not at all.
    u : array_like, shape (p,), optional
        Input.

    Returns
    -------
    x_prior : ndarray, shape (n,)
        Projected state.
    P_prior : ndarray, shape (n, n)
        Projected covariance.

    See Also
    --------
    update : the measurement update before it.

    Examples
    --------
    The 1-D filter of :func:`update` projected one step with ``A = 1`` and process noise 0.5: the variance grows.

    >>> x, P = predict([0.8], [[0.8]], A=[[1.0]], Q=[[0.5]])
    >>> np.round(x, 3), np.round(P, 3)
    (array([0.8]), array([[1.3]]))
    """
    d = _model(x=x, P=P, A=A, Q=Q, B=B, u=u, optional=("B", "u"))
    Bu = None if B is None else d["B"] @ d["u"]
    return _predict(d["x"], d["P"], d["A"], d["Q"], Bu)


def seed000_labcode_kalman(x, P, z, A, Q, H, R):
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
    d = _model(x=x, P=P, z=z, A=A, Q=Q, H=H, R=R)
    x, P, z, A, Q, H, R = (d[k] for k in "x P z A Q H R".split())
    K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)                     # (000 §4.4.3, printed code)
    x = x + K @ (z - H @ x)                                          # (000 §4.4.3, printed code)
    P = P - K @ H @ P                                                # (000 §4.4.3, printed code)
    P = A @ P @ A.T + Q                                              # (000 §4.4.3, printed code)
    return x, P


# ----------------------------------------------------------------------------------------------------------------
# Part C: the filter (000 §4.3.1 and §4.4.3)
# ----------------------------------------------------------------------------------------------------------------

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

    def __init__(self, A, B, u, Q, R, H, x0, P0, covariance="joseph", project_state=True, control=True):
        d = _model(x=x0, P=P0, A=A, Q=Q, H=H, R=R, B=B, u=u, names={"x": "x0", "P": "P0"})
        self.A, self.B, self.u, self.Q, self.R, self.H = (d[k] for k in ("A", "B", "u", "Q", "R", "H"))
        self.x, self.P = d["x"].copy(), d["P"].copy()
        self.covariance = _check_form(covariance)
        self.project_state, self.control = bool(project_state), bool(control)
        self.x_post = self.P_post = self.K = None

    @classmethod
    def falling_body(cls, x0=(200.0, 0.0), P0=None, mn_std=12.0, pn_std=0.4, k=0.25, m=10.0, g=9.8, dt=0.01,
                     **options):
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
            Gravity, m/s².
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
        mn_std, pn_std = _scalar(mn_std, "mn_std", True), _scalar(pn_std, "pn_std", True)
        P0 = mn_std ** 2 * np.eye(2) if P0 is None else P0
        return cls(A, B, u, pn_std ** 2 * np.eye(2), mn_std ** 2 * np.eye(2), np.eye(2), x0, P0, **options)

    def step(self, z):
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
        z = _exact(z, "z", (self.H.shape[0],))
        self.x_post, self.P_post, self.K = _update(self.x, self.P, z, self.H, self.R, self.covariance)
        Bu = self.B @ self.u if self.control else None
        x_next, self.P = _predict(self.x_post, self.P_post, self.A, self.Q, Bu)
        self.x = x_next if self.project_state else self.x_post       # printed code: s.x is never projected
        return self.x_post, self.P_post

    def run(self, zs):
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
        out = {"x": np.empty((len(zs), n)), "P": np.empty((len(zs), n, n)), "x_prior": np.empty((len(zs), n)),
               "P_prior": np.empty((len(zs), n, n)), "K": np.empty((len(zs), n, m))}
        for i, z in enumerate(zs):
            out["x_prior"][i], out["P_prior"][i] = self.x, self.P
            out["x"][i], out["P"][i] = self.step(z)
            out["K"][i] = self.K
        return out


def kf_batch(zs, A, B, u, Q, R, H, x0, P0, covariance="joseph", project_state=True, control=True):
    """:class:`ThesisKF` over many runs at once (the fast twin; tests assert both agree).

    The covariance and gain sequences do not depend on the measurements, so they are computed once and shared;
    the states of all runs are updated together.

    Parameters
    ----------
    zs : array_like, shape (R, N, m)
        R runs of N measurements.
    A : array_like, shape (n, n)
        Transition matrix.
    B : array_like, shape (n, p)
        Input matrix.
    u : array_like, shape (p,)
        Input.
    Q : array_like, shape (n, n)
        Process noise covariance.
    R : array_like, shape (m, m)
        Measurement noise covariance.
    H : array_like, shape (m, n)
        Measurement matrix.
    x0 : array_like, shape (n,) or (R, n)
        Initial estimate, the same for every run or one per run.
    P0 : array_like, shape (n, n)
        Its covariance.
    covariance : {'joseph', 'short', 'information'}, optional
        As :class:`ThesisKF`.
    project_state : bool, optional
        As :class:`ThesisKF`.
    control : bool, optional
        As :class:`ThesisKF`.

    Returns
    -------
    dict of ndarray
        ``x`` (R, N, n) posteriors, ``x_prior`` (R, N, n), ``P`` (N, n, n) posterior covariances,
        ``P_prior`` (N, n, n), ``K`` (N, n, m).
    """
    d = _model(P=P0, A=A, Q=Q, H=H, R=R, B=B, u=u, names={"P": "P0"})
    A, Q, H, Rm, P = d["A"], d["Q"], d["H"], d["R"], d["P"]
    n, m = H.shape[1], H.shape[0]
    zs = validate.array(zs, "zs")
    if zs.ndim != 3 or zs.shape[2] != m:
        raise ValueError(f"zs must have shape (R, N, {m}); got {zs.shape}")
    runs, N = zs.shape[:2]
    x = validate.array(x0, "x0")
    if x.shape not in ((n,), (runs, n)):
        raise ValueError(f"x0 must have shape ({n},) or ({runs}, {n}); got {x.shape}")
    x = np.broadcast_to(x, (runs, n)).copy()
    form = _check_form(covariance)
    Bu = d["B"] @ d["u"] if control else np.zeros(n)
    out = {"x": np.empty((runs, N, n)), "x_prior": np.empty((runs, N, n)), "P": np.empty((N, n, n)),
           "P_prior": np.empty((N, n, n)), "K": np.empty((N, n, m))}
    for i in range(N):
        out["x_prior"][:, i], out["P_prior"][i] = x, P
        K = _gain(P, H, Rm)                                          # (000 eq 4.31)
        x = x + (zs[:, i] - x @ H.T) @ K.T                           # (000 eq 4.8), all runs at once
        if form == "joseph":
            P = _joseph(P, K, H, Rm)                                 # (000 eq 4.17)
        elif form == "short":
            P = (np.eye(n) - K @ H) @ P                              # (000 §4.3.1 alternate form)
        else:
            P = np.linalg.inv(np.linalg.inv(P) + H.T @ np.linalg.inv(Rm) @ H)   # (000 §4.3.1 alternate form)
        out["x"][:, i], out["P"][i], out["K"][i] = x, P, K
        if project_state:
            x = x @ A.T + Bu                                         # (000 eq 4.32 + G u)
        P = A @ P @ A.T + Q                                          # (000 eq 4.36)
    return out


def simulate_falling_body(n_runs, seed, n_steps=199, first_run=0, x0=200.0, v0=0.0, k=0.25, m=10.0, g=9.8,
                          dt=0.01, pn_std=0.4, mn_std=12.0):
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
        Gravity, m/s².
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
    n_runs, n_steps = _count(n_runs, "n_runs"), _count(n_steps, "n_steps")
    seed, first_run = _count(seed, "seed", 0), _count(first_run, "first_run", 0)
    A, B, u = falling_body_state_space(k, m, g, dt)
    pn_std, mn_std = validate.scalar(pn_std, "pn_std", nonnegative=True), validate.scalar(mn_std, "mn_std",
                                                                                          nonnegative=True)
    noise = np.stack([np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(r,)))
                      .standard_normal((n_steps, 4)) for r in range(first_run, first_run + n_runs)])
    truth = np.empty((n_runs, n_steps + 1, 2))
    truth[:, 0] = _scalar(x0, "x0"), _scalar(v0, "v0")
    Bu = B @ u
    for i in range(n_steps):
        truth[:, i + 1] = truth[:, i] @ A.T + Bu + pn_std * noise[:, i, :2]   # (000 §4.4.3 d, eq 4.1)
    z = truth[:, 1:] + mn_std * noise[:, :, 2:]                              # (000 §4.4.3 d, eq 4.3, H = I)
    return truth, z


def nees(err, P):
    """Normalised estimation error squared ``εᵀ P⁻¹ ε`` (an addition: the standard consistency test, not in the seed).

    For a consistent filter its mean over runs is the state dimension n (here 2).

    Parameters
    ----------
    err : array_like, shape (..., n)
        Estimate minus truth.
    P : array_like, shape (..., n, n)
        The filter's covariance for that estimate (broadcasts against ``err``).

    Returns
    -------
    ndarray, shape (...)
        The NEES of each estimate (dimensionless).

    Examples
    --------
    >>> float(nees([1.0, 2.0], np.diag([1.0, 4.0])))
    2.0
    """
    err = validate.array(err, "err")
    P = validate.array(P, "P")
    if err.ndim < 1 or P.ndim < 2 or P.shape[-2:] != (err.shape[-1], err.shape[-1]):
        raise ValueError(f"P must have shape (..., {err.shape[-1] if err.ndim else 'n'}, "
                         f"{err.shape[-1] if err.ndim else 'n'}) to match err {err.shape}; got {P.shape}")
    validate.broadcast({"err": 1, "P": 2}, err=err, P=P)
    sol = np.linalg.solve(P, err[..., None])[..., 0]
    return np.einsum("...i,...i->...", err, sol)


def nees_bounds(n_runs, dim=2, prob=0.95):
    """Two-sided ``prob`` interval of the *run-averaged* NEES of a consistent filter: ``χ²(n_runs·dim) / n_runs``.

    Parameters
    ----------
    n_runs : int
        Number of Monte-Carlo runs averaged.
    dim : int, optional
        State dimension n.
    prob : float, optional
        Probability of the interval, in (0, 1).

    Returns
    -------
    lo : float
        Lower bound of the run-averaged NEES.
    hi : float
        Upper bound.
    """
    n_runs, dim = _count(n_runs, "n_runs"), _count(dim, "dim")
    prob = _scalar(prob, "prob", True)
    if prob >= 1:
        raise ValueError(f"prob must be in (0, 1); got {prob!r}")
    lo, hi = chi2.ppf([(1 - prob) / 2, (1 + prob) / 2], n_runs * dim)
    return lo / n_runs, hi / n_runs


def steady_state(A, H, Q, R):
    """Steady-state prior covariance, gain and posterior covariance from the discrete algebraic Riccati equation.

    The prior covariance of the thesis' loop converges to the solution of
    ``P = A P Aᵀ - A P Hᵀ (H P Hᵀ + R)⁻¹ H P Aᵀ + Q`` (``scipy.linalg.solve_discrete_are`` with ``a = Aᵀ``,
    ``b = Hᵀ``; an addition, the thesis does not discuss the steady state). For the lab:
    K ≈ [[0.0338, 0.0046], [0.0046, 0.0322]], prior P ≈ [[5.04, 0.71], [0.71, 4.79]].

    Parameters
    ----------
    A : array_like, shape (n, n)
        Transition matrix.
    H : array_like, shape (m, n)
        Measurement matrix.
    Q : array_like, shape (n, n)
        Process noise covariance.
    R : array_like, shape (m, m)
        Measurement noise covariance.

    Returns
    -------
    P_prior : ndarray, shape (n, n)
        Steady-state prior covariance.
    K : ndarray, shape (n, m)
        Steady-state gain.
    P_post : ndarray, shape (n, n)
        Steady-state posterior covariance.
    """
    d = _model(A=A, H=H, Q=Q, R=R)
    A, H, Q, R = d["A"], d["H"], d["Q"], d["R"]
    P = solve_discrete_are(A.T, H.T, Q, R)
    K = _gain(P, H, R)                                               # (000 eq 4.31)
    return P, K, _joseph(P, K, H, R)                                 # (000 eq 4.17)


def monte_carlo(n_runs=200, seed=2, batch=50, variants=None, progress=True, n_steps=199, **model):
    """Seeded Monte Carlo of the lab's filter variants on the same simulated falling bodies (000 §4.4.3).

    Runs are simulated with :func:`simulate_falling_body` in batches of ``batch`` (run r is the same whatever the
    batch size) and filtered with :func:`kf_batch`; a tqdm bar counts runs.

    Parameters
    ----------
    n_runs : int, optional
        Number of runs.
    seed : int, optional
        The Monte-Carlo seed.
    batch : int, optional
        Runs simulated and filtered together.
    variants : dict, optional
        Name -> dict of :func:`kf_batch` options (``covariance``, ``project_state``, ``control``, ``x0``, ``P0``,
        ``Q``, ``R``), or None for the lab's two: ``'thesis filter'`` (with the state projection) and
        ``'printed code'`` (without it, short form).
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

    n_runs, batch = _count(n_runs, "n_runs"), _count(batch, "batch")
    n_steps, seed = _count(n_steps, "n_steps"), _count(seed, "seed", 0)
    validate.options(model, [k_ for k_ in LAB2 if k_ != "tmax"], "monte_carlo")
    model = {k_: validate.scalar(v, k_, positive=k_ in ("k", "m", "dt", "mn_std"),
                                 nonnegative=k_ == "pn_std") for k_, v in model.items()}
    p = dict(LAB2)
    p.update(model)
    A, B, u = falling_body_state_space(p["k"], p["m"], p["g"], p["dt"])
    base = dict(A=A, B=B, u=u, Q=p["pn_std"] ** 2 * np.eye(2), R=p["mn_std"] ** 2 * np.eye(2), H=np.eye(2),
                x0=np.array([p["x0"], p["v0"]]), P0=p["mn_std"] ** 2 * np.eye(2))
    if variants is None:
        variants = {"thesis filter": {}, "printed code": {"project_state": False, "covariance": "short"}}
    if not isinstance(variants, dict) or not variants:
        raise ValueError(f"variants must be a non-empty dict name -> kf_batch options; got {variants!r}")
    for name, opts in variants.items():
        validate.options(opts, ("covariance", "project_state", "control", "x0", "P0", "Q", "R"),
                         f"monte_carlo variant {name!r}")
    sims = {k_: p[k_] for k_ in ("x0", "v0", "k", "m", "g", "dt", "pn_std", "mn_std")}
    sq_meas = np.zeros(2)
    acc = {name: {"sq": np.zeros((n_steps, 2)), "err": np.zeros((n_steps, 2)), "nees": np.zeros(n_steps)}
           for name in variants}
    P_of = {}
    with tqdm(total=n_runs, desc="Monte Carlo", unit="run", disable=not progress) as bar:
        for start in range(0, n_runs, batch):
            nb = min(batch, n_runs - start)
            truth, z = simulate_falling_body(nb, seed, n_steps=n_steps, first_run=start, **sims)
            sq_meas += ((z - truth[:, 1:]) ** 2).sum(axis=(0, 1))
            for name, opts in variants.items():
                res = kf_batch(z, **{**base, **opts})
                e = res["x"] - truth[:, 1:]
                acc[name]["sq"] += (e ** 2).sum(axis=0)
                acc[name]["err"] += e.sum(axis=0)
                acc[name]["nees"] += nees(e, res["P"][None]).sum(axis=0)
                P_of[name] = res["P"]
            bar.update(nb)
    out = {"n_runs": n_runs, "seed": seed, "meas_rms": np.sqrt(sq_meas / (n_runs * n_steps)), "variants": {}}
    for name, a in acc.items():
        out["variants"][name] = {"rms": np.sqrt(a["sq"].sum(axis=0) / (n_runs * n_steps)),
                                 "rms_t": np.sqrt(a["sq"] / n_runs), "mean_err_t": a["err"] / n_runs,
                                 "nees_t": a["nees"] / n_runs, "P": P_of[name]}
    return out
