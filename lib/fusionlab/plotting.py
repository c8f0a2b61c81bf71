"""Figures of frames and attitudes: triads, an aircraft, and the Euler sequence of seed 001 (figs 2-5).

Every helper takes attitudes in the library convention (:mod:`fusionlab.rotations`): ``C_bn`` body→NED, columns
are the body axes written in North-East-Down coordinates, ``euler = [roll, pitch, yaw]`` in radians. Degrees appear
only in titles.

Display mapping
---------------
NED is drawn the way a reader expects to see the world: Down points down on the screen. The 3-D axes show
``(x, y, z) = (East, North, Up = -Down)`` (:func:`ned_to_display`). This is a proper rotation of NED (det +1), so
nothing is mirrored: positive yaw still turns the nose clockwise seen from above, the right wing is on the right.
(Plotting ``(North, East, -Down)`` directly would be a reflection and draw every attitude mirror-imaged.)

Artists that draw a frame axis carry a ``gid`` such as ``'B:x'`` (body x axis), so tests and notebooks can find
them in a figure.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import matplotlib.pyplot as plt
import numpy as np
from numpy.typing import ArrayLike
from matplotlib.lines import Line2D
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from . import rotations, validate

if TYPE_CHECKING:
    from matplotlib.artist import Artist
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure
    from matplotlib.patches import Rectangle
    from mpl_toolkits.mplot3d.axes3d import Axes3D

__all__ = [
    "NED_TO_DISPLAY",
    "ned_to_display",
    "setup_ned_axes",
    "draw_triad",
    "draw_aircraft",
    "euler_frames",
    "plot_euler_frames",
    "plot_gimbal_lock",
]

#: Rows pick (East, North, -Down) out of (North, East, Down); det = +1, so no mirror image.
NED_TO_DISPLAY = np.array(
    [
        [0.0, 1.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 0.0, -1.0],
    ]
)

GREY, RED = "0.6", "tab:red"
AXIS_COLORS = ("tab:red", "tab:green", "tab:blue")


def ned_to_display(v: ArrayLike) -> np.ndarray:
    """NED vectors to the plotted coordinates ``(East, North, Up)``.

    Parameters
    ----------
    v : array_like, shape (..., 3)
        Vectors or points in NED.

    Returns
    -------
    ndarray, shape (..., 3)
        ``[v_E, v_N, -v_D]``.

    Examples
    --------
    >>> ned_to_display([1.0, 2.0, 3.0])        # 1 north, 2 east, 3 down
    array([ 2.,  1., -3.])
    """
    v = validate.vectors(v, "v")
    return v @ NED_TO_DISPLAY.T


def setup_ned_axes(ax: Axes3D, lim: float = 1.2, elev: float = 25, azim: float = -70) -> Axes3D:
    """Label a 3-D axis for NED data drawn with :func:`ned_to_display`: equal aspect, Down pointing down.

    Parameters
    ----------
    ax : mpl_toolkits.mplot3d.axes3d.Axes3D
        The axis to set up.
    lim : float, optional
        Half-width of the cube shown, in the units of the data.
    elev : float, optional
        Camera elevation, degrees.
    azim : float, optional
        Camera azimuth, degrees (default: from the south, slightly east and above: East to the right, North into
        the page, Down down).
    """
    lim = validate.positive(lim, "lim")
    ax.set(xlim=(-lim, lim), ylim=(-lim, lim), zlim=(-lim, lim), xlabel="East", ylabel="North", zlabel="Up (= -Down)")
    ax.set_box_aspect((1, 1, 1), zoom=1.15)
    ax.view_init(elev=elev, azim=azim)
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        axis.set_ticklabels([])  # unit vectors: the grid is enough, numbers clutter
        axis.labelpad = -12
    return ax


def _colors(colors):
    return [colors] * 3 if isinstance(colors, str) else list(colors)


def draw_triad(
    ax: Axes3D,
    C: ArrayLike,
    origin: ArrayLike = (0, 0, 0),
    colors: str | Sequence[str] = AXIS_COLORS,
    label: str | None = None,
    alpha: float = 1.0,
    length: float = 1.0,
    lw: float = 2.0,
    label_at: float = 1.15,
) -> list[Artist]:
    """Draw the three columns of ``C`` as arrows labelled ``x_label``, ``y_label``, ``z_label``.

    Parameters
    ----------
    ax : mpl_toolkits.mplot3d.axes3d.Axes3D
        A 3-D axis set up with :func:`setup_ned_axes`.
    C : array_like, shape (3, 3)
        Columns are the frame's unit axes in NED (e.g. ``C_bn``).
    origin : array_like, shape (3,), optional
        NED point the arrows start from, data units.
    colors : str or sequence of str, optional
        One colour for the whole triad, or one per axis.
    label : str, optional
        Frame name used as subscript (``'B'`` gives x_B ...) and in the artists' gid.
    alpha : float, optional
        Opacity.
    length : float, optional
        Arrow length, data units.
    lw : float, optional
        Line width, points.
    label_at : float, optional
        Axis labels sit at ``label_at * length`` along each axis (move them apart when two triads share an axis).

    Returns
    -------
    list of matplotlib.artist.Artist
        Shaft lines (gid ``'{label}:x'`` ...), arrow heads and labels.
    """
    C = validate.matrices(C, "C")
    if C.shape != (3, 3):
        raise ValueError(f"C must have shape (3, 3); got {C.shape}")
    o = ned_to_display(validate.vectors(origin, "origin"))
    tips = ned_to_display(length * C.T)  # row k: axis k in display coordinates
    artists = []
    for k, (name, color) in enumerate(zip("xyz", _colors(colors))):
        d = tips[k]
        gid = f"{label}:{name}" if label is not None else None
        artists += ax.plot(*np.stack([o, o + d]).T, color=color, alpha=alpha, lw=lw, gid=gid)
        head = 0.18 * d  # the quiver draws only the head of the arrow
        artists.append(ax.quiver(*(o + d - head), *head, color=color, alpha=alpha, lw=lw, arrow_length_ratio=1.0))
        text = f"${name}_{{{label}}}$" if label is not None else name
        artists.append(
            ax.text(*(o + label_at * d), text, color=color, alpha=alpha, fontsize=10, ha="center", va="center")
        )
    return artists


# Aircraft outline in body coordinates (x nose, y right wing, z down), in units of `scale`.
_FUSELAGE = np.array([[0.9, 0, 0], [-0.85, 0, 0]])
_WINGS = np.array(
    [
        [0.2, 0, 0],
        [-0.1, 0.85, 0],
        [-0.28, 0.85, 0],
        [-0.2, 0, 0],
        [-0.28, -0.85, 0],
        [-0.1, -0.85, 0],
    ]
)
_STABILISER = np.array(
    [
        [-0.6, 0, 0],
        [-0.75, 0.3, 0],
        [-0.85, 0.3, 0],
        [-0.82, 0, 0],
        [-0.85, -0.3, 0],
        [-0.75, -0.3, 0],
    ]
)
_FIN = np.array([[-0.55, 0, 0], [-0.78, 0, -0.35], [-0.88, 0, -0.35], [-0.82, 0, 0]])  # -z: up when level


def draw_aircraft(ax: Axes3D, C_bn: ArrayLike, scale: float = 1.0, color: str = "lightsteelblue") -> list[Artist]:
    """Draw a simple aircraft at attitude ``C_bn``: fuselage on body x, wings on body y, fin toward body -z.

    The right (starboard) wing tip carries a green light, the left (port) one a red light, as on real aircraft,
    so the sign of roll can be read off the picture.

    Parameters
    ----------
    ax : mpl_toolkits.mplot3d.axes3d.Axes3D
        A 3-D axis set up with :func:`setup_ned_axes`.
    C_bn : array_like, shape (3, 3)
        Body→NED attitude.
    scale : float, optional
        Half-length of the fuselage is about ``0.9 * scale`` (data units).
    color : str, optional
        Colour of the airframe.

    Returns
    -------
    list of matplotlib.artist.Artist
        The airframe, the fin and the wing-tip lights.
    """
    C_bn = validate.matrices(C_bn, "C_bn")
    scale = validate.positive(scale, "scale")

    def place(pts_b):  # body points -> display points
        return ned_to_display(scale * pts_b @ C_bn.T)

    body = [place(p) for p in (_WINGS, _STABILISER, _FIN)]
    poly = Poly3DCollection(body, facecolor=color, edgecolor="navy", linewidths=0.8, alpha=0.8)
    artists = [ax.add_collection3d(poly)]
    artists += ax.plot(*place(_FUSELAGE).T, color="navy", lw=3, solid_capstyle="round", gid="aircraft")
    lights = place(np.array([[-0.19, 0.85, 0], [-0.19, -0.85, 0]]))
    artists.append(ax.scatter(*lights.T, c=["tab:green", "tab:red"], s=18, depthshade=False))
    return artists


# --------------------------------------------------------------------------------------------------------------
# The Euler sequence (seed 001, Euler note figs 2-4) and gimbal lock (fig 5)
# --------------------------------------------------------------------------------------------------------------


def _deg(a):
    """Angle in rad as a short degree string: 40°, -10°, 12.5° (never -0°)."""
    return f"{round(float(np.degrees(a)), 1) + 0.0:g}°"


def _euler(euler):
    e = validate.vectors(euler, "euler")
    if e.shape != (3,):
        raise ValueError(f"euler must have shape (3,) = [roll, pitch, yaw]; got {e.shape}")
    return validate.angles_rad(e, "euler")


def _angle(x, name):
    a = validate.angles_rad(x, name)
    if a.shape != ():
        raise ValueError(f"{name} must be a scalar angle in rad; got shape {a.shape}")
    return float(a)


def euler_frames(euler: ArrayLike) -> dict[str, np.ndarray]:
    """The four frames of the Z-Y-X sequence as DCMs to NED (columns = the frame's axes in NED).

    Parameters
    ----------
    euler : array_like, shape (3,)
        ``[roll, pitch, yaw]``, rad.

    Returns
    -------
    dict of ndarray
        ``{'I': I, 'v1': Rz(ψ), 'v2': Rz(ψ) Ry(θ), 'B': Rz(ψ) Ry(θ) Rx(φ) = C_bn}``, each of shape (3, 3).
    """
    roll, pitch, yaw = _euler(euler)
    v1 = rotations.rot_z(yaw)  # yaw about z_I        (001 Euler §3)
    v2 = v1 @ rotations.rot_y(pitch)  # pitch about y_v1     (001 Euler §4)
    return {"I": np.eye(3), "v1": v1, "v2": v2, "B": v2 @ rotations.rot_x(roll)}  # roll about x_v2 (§5)


def _arc(ax, C_prev, rot, angle, moving, radius=0.5):
    """Arc swept by axis ``moving`` (0, 1, 2) of frame ``C_prev`` as it turns by ``angle`` under ``rot``."""
    if abs(angle) < 1e-9:
        return
    R = rot(np.linspace(0.0, angle, 40))  # (40, 3, 3)
    pts = ned_to_display(radius * (C_prev @ R)[:, :, moving])
    ax.plot(*pts.T, color="k", lw=1.2)
    ax.quiver(*pts[-2], *(pts[-1] - pts[-2]), color="k", arrow_length_ratio=8.0, lw=1.2)


def _new_axes(n, ax, figsize):
    if ax is None:
        fig = plt.figure(figsize=figsize)
        return fig, [fig.add_subplot(1, n, i + 1, projection="3d") for i in range(n)]
    axes = list(np.atleast_1d(ax))
    if len(axes) != n or not all(getattr(a, "name", "") == "3d" for a in axes):
        raise ValueError(f"ax must be None or {n} 3-D axes; got {ax!r}")
    return axes[0].figure, axes


def plot_euler_frames(euler: ArrayLike, ax: Axes3D | Sequence[Axes3D] | None = None, stages: bool = True) -> Figure:
    """Draw the Euler sequence I → v1 (yaw) → v2 (pitch) → B (roll), as in seed 001 figs 2-4.

    Parameters
    ----------
    euler : array_like, shape (3,)
        ``[roll, pitch, yaw]``, rad.
    ax : Axes3D or sequence of 4 Axes3D, optional
        Where to draw: 4 axes (``stages=True``) or one (``stages=False``); a new figure when None.
    stages : bool, optional
        True: four panels, each the previous frame in grey and the new one in red, with the arc the moving axis
        sweeps; False: one panel with all four frames and the aircraft.

    Returns
    -------
    matplotlib.figure.Figure
        Not shown (end the notebook line with ``;``).

    Raises
    ------
    ValueError
        If ``euler`` is not a finite (3,) array in radians.
    """
    roll, pitch, yaw = _euler(euler)
    F = euler_frames([roll, pitch, yaw])
    angles = f"(φ, θ, ψ) = ({_deg(roll)}, {_deg(pitch)}, {_deg(yaw)})"
    if not stages:
        fig, (ax,) = _new_axes(1, None if ax is None else [ax], (6, 6))
        setup_ned_axes(ax)
        for name, color, alpha in (
            ("I", GREY, 1.0),
            ("v1", "tab:orange", 0.5),
            ("v2", "tab:purple", 0.5),
            ("B", RED, 1.0),
        ):
            draw_triad(
                ax,
                F[name],
                colors=color,
                label=name,
                alpha=alpha,
                lw=2.5 if name == "B" else 1.5,
                label_at=1.35 if name in ("v1", "v2") else 1.15,
            )
        draw_aircraft(ax, F["B"], scale=0.6)
        ax.set_title(f"{angles}: body frame B (red) reached from NED (grey)\nvia v1 (yaw) and v2 (pitch)", fontsize=10)
        return fig

    fig, axes = _new_axes(4, ax, (17, 5))
    steps = [
        ("yaw ψ", yaw, rotations.rot_z, "z", "I", "v1", 0),  # (name, angle, rot, about, prev, new, arc)
        ("pitch θ", pitch, rotations.rot_y, "y", "v1", "v2", 0),
        ("roll φ", roll, rotations.rot_x, "x", "v2", "B", 1),
    ]
    setup_ned_axes(axes[0])
    draw_triad(axes[0], F["I"], colors=GREY, label="I")
    axes[0].set_title("start: inertial frame I\n(North-East-Down, Down drawn down)", fontsize=10)
    for a, (name, angle, rot, about, prev, new, moving) in zip(axes[1:], steps):
        setup_ned_axes(a)
        draw_triad(a, F[prev], colors=GREY, label=prev, lw=1.5, label_at=1.35)
        draw_triad(a, F[new], colors=RED, label=new, lw=2.5)
        _arc(a, F[prev], rot, angle, moving)
        a.set_title(f"{name} = {_deg(angle)} about ${about}_{{{prev}}}$\n→ frame {new}", fontsize=10)
    draw_aircraft(axes[3], F["B"], scale=0.6)
    fig.suptitle(
        f"Euler angles {angles}: yaw about $z_I$, then pitch about the new y, then roll about the "
        f"newest x;  $C_{{bn}} = R_z(ψ)\\,R_y(θ)\\,R_x(φ)$",
        fontsize=12,
    )
    fig.legend(
        handles=[
            Line2D([], [], color=GREY, lw=1.5, label="previous frame"),
            Line2D([], [], color=RED, lw=2.5, label="new frame"),
            Line2D([], [], color="k", lw=1.2, label="path of the turning axis"),
        ],
        loc="lower center",
        ncol=3,
        frameon=False,
    )
    fig.subplots_adjust(left=0.0, right=1.0, bottom=0.08, top=0.85, wspace=0.02)
    return fig


def plot_gimbal_lock(roll: float, yaw: float, pitch: float = np.pi / 2) -> Figure:
    """Two (roll, yaw) pairs that give the same body triad at θ = ±90° (seed 001 Euler note §6, fig 5).

    At θ = +90° only ``φ - ψ`` is observable, at θ = -90° only ``φ + ψ`` (Lab 01 shows why). The second pair keeps that
    combination and sets yaw to 0 -- exactly what :func:`rotations.dcm_to_euler` reports at lock (if ``yaw`` is
    already 0 the second pair shifts roll and yaw by 60° instead). Away from ±90° the two pairs differ, and the
    figure says so.

    Parameters
    ----------
    roll : float
        Roll of the first pair, rad.
    yaw : float
        Yaw of the first pair, rad.
    pitch : float, optional
        The pitch shared by both pairs, rad.

    Returns
    -------
    matplotlib.figure.Figure
        Three panels: pair A, pair B, both triads overlaid.
    """
    roll, yaw, pitch = _angle(roll, "roll"), _angle(yaw, "yaw"), _angle(pitch, "pitch")
    s = 1.0 if pitch >= 0 else -1.0  # +90°: φ - ψ kept; -90°: φ + ψ kept
    delta = -s * yaw if abs(yaw) > 1e-9 else np.pi / 3
    pairs = {"A": (roll, yaw), "B": (roll + delta, yaw + s * delta)}
    C = {k: rotations.euler_to_dcm([r, pitch, y]) for k, (r, y) in pairs.items()}
    diff = float(np.max(np.abs(C["A"] - C["B"])))
    combo, sign = ("φ − ψ", -1.0) if s > 0 else ("φ + ψ", 1.0)

    fig, axes = _new_axes(3, None, (14, 5.2))
    for a, k, color in zip(axes, "AB", (RED, "tab:blue")):
        setup_ned_axes(a)
        draw_triad(a, np.eye(3), colors=GREY, label="I", lw=1.0, alpha=0.6)
        draw_triad(a, C[k], colors=color, label=k)
        draw_aircraft(a, C[k], scale=0.6)
        r, y = pairs[k]
        a.set_title(
            f"pair {k}: φ = {_deg(r)}, ψ = {_deg(y)}, θ = {_deg(pitch)}\n{combo} = {_deg(r + sign * y)}", fontsize=10
        )
    setup_ned_axes(axes[2])
    draw_triad(axes[2], C["A"], colors=RED, label="A", lw=4, alpha=0.5, label_at=1.4)
    draw_triad(axes[2], C["B"], colors="tab:blue", label="B", lw=1.5)
    axes[2].set_title(f"A and B overlaid: max |C_A − C_B| = {diff:.1e}", fontsize=10)

    if diff < 1e-9:
        finding = (
            f"At θ = {_deg(pitch)} roll and yaw turn about the same line: only {combo} is observable, "
            f"so pairs A and B give the same attitude"
        )
    else:
        finding = (
            f"At θ = {_deg(pitch)} roll and yaw are distinct: keeping {combo} is not enough, "
            f"A and B are different attitudes"
        )
    fig.suptitle(finding, fontsize=12)
    fig.subplots_adjust(left=0.0, right=1.0, bottom=0.02, top=0.82, wspace=0.02)
    return fig


# ----------------------------------------------------------------------------------------------------------------
# Lab 02: Kalman-filter figures (seed 000 §4.2-4.4)
# ----------------------------------------------------------------------------------------------------------------

from . import kalman as _kalman  # noqa: E402  (a seed-method module; plotting sits above it)

__all__ += ["plot_gaussian_product", "plot_kf_run"]


def _gauss_pdf(x, mu, var):
    return np.exp(-0.5 * (x - mu) ** 2 / var) / np.sqrt(2 * np.pi * var)


def plot_gaussian_product(
    mu1: float,
    var1: float,
    mu2: float,
    var2: float,
    ax: Axes | None = None,
    labels: tuple[str, ...] = ("prediction", "measurement"),
) -> Figure:
    """Two 1-D Gaussians and their normalised product (seed 000 figs 24-25), on one axis.

    Parameters
    ----------
    mu1 : float
        Mean of the first (the prediction).
    var1 : float
        Its variance, unit of ``mu1`` squared.
    mu2 : float
        Mean of the second (the measurement), same unit as ``mu1``.
    var2 : float
        Its variance.
    ax : matplotlib.axes.Axes, optional
        Draw here (a new figure otherwise).
    labels : tuple of str, optional
        Legend names of the two inputs.

    Returns
    -------
    matplotlib.figure.Figure
        Lines carry gids ``'g1'``, ``'g2'``, ``'product'``.
    """
    mu, var = _kalman.gaussian_product(mu1, var1, mu2, var2)
    sd = np.sqrt([var1, var2])
    lo = min(mu1 - 4 * sd[0], mu2 - 4 * sd[1])
    hi = max(mu1 + 4 * sd[0], mu2 + 4 * sd[1])
    x = np.linspace(lo, hi, 600)
    if ax is None:
        fig, ax = plt.subplots(figsize=(7, 3.5))
    else:
        fig = ax.figure
    ax.plot(
        x, _gauss_pdf(x, mu1, var1), color="tab:blue", gid="g1", label=f"{labels[0]}: μ = {mu1:.2f}, σ² = {var1:.2f}"
    )
    ax.plot(
        x, _gauss_pdf(x, mu2, var2), color="tab:red", gid="g2", label=f"{labels[1]}: μ = {mu2:.2f}, σ² = {var2:.2f}"
    )
    ax.plot(
        x,
        _gauss_pdf(x, mu, var),
        color="tab:green",
        lw=2.5,
        gid="product",
        label=f"product: μ = {mu:.2f}, σ² = {var:.2f}",
    )
    ax.axvline(mu, color="tab:green", ls=":", lw=1)
    ax.set_xlabel("position (m)")
    ax.set_ylabel("probability density (1/m)")
    ax.set_title("The product is narrower than either input and sits nearer the sharper one")
    ax.legend(fontsize=9, loc="upper right")
    ax.grid(alpha=0.3)
    return fig


def plot_kf_run(
    t: ArrayLike,
    truth: ArrayLike,
    z: ArrayLike,
    x: ArrayLike,
    P: ArrayLike,
    component: int = 0,
    name: str = "position",
    unit: str = "m",
    title: str | None = None,
) -> Figure:
    """One filter run: truth, measurements and estimate (top) and the estimate's error with its ±2σ band (bottom).

    Parameters
    ----------
    t : array_like, shape (N,)
        Times of the measurements, s.
    truth : array_like, shape (N, n)
        True state at those times.
    z : array_like, shape (N, n)
        Measurements (H = I).
    x : array_like, shape (N, n)
        Posterior estimates.
    P : array_like, shape (N, n, n)
        The filter's posterior covariance.
    component : int, optional
        Which state to draw (0 = position, 1 = velocity for the falling body).
    name : str, optional
        Name of the state, for the labels.
    unit : str, optional
        Its unit, for the labels.
    title : str, optional
        Title of the top panel (default: a sentence naming the state).

    Returns
    -------
    matplotlib.figure.Figure
        Two axes.
    """
    t = validate.array(t, "t")
    truth, z, x = (validate.array(a, nm) for a, nm in ((truth, "truth"), (z, "z"), (x, "x")))
    P = validate.array(P, "P")
    N = len(t)
    for a, nm in ((truth, "truth"), (z, "z"), (x, "x")):
        if a.ndim != 2 or a.shape[0] != N:
            raise ValueError(f"{nm} must have shape ({N}, n) to match t; got {a.shape}")
    if P.shape != (N, x.shape[1], x.shape[1]):
        raise ValueError(f"P must have shape ({N}, {x.shape[1]}, {x.shape[1]}); got {P.shape}")
    c = component
    sd2 = 2 * np.sqrt(P[:, c, c])
    fig, (ax0, ax1) = plt.subplots(2, 1, figsize=(8, 6), sharex=True, gridspec_kw={"height_ratios": [3, 2]})
    ax0.plot(t, z[:, c], ".", color="tab:red", ms=3, alpha=0.6, label=f"measured {name}")
    ax0.plot(t, truth[:, c], color="tab:blue", lw=2, label=f"true {name}")
    ax0.plot(t, x[:, c], color="tab:green", lw=1.5, label="filtered estimate")
    ax0.fill_between(t, x[:, c] - sd2, x[:, c] + sd2, color="tab:green", alpha=0.2, label="estimate ± 2σ")
    ax0.set_ylabel(f"{name} ({unit})")
    ax0.legend(fontsize=9)
    ax0.grid(alpha=0.3)
    ax0.set_title(title or f"Falling object: the filter follows the true {name} through the measurement noise")
    ax1.plot(t, x[:, c] - truth[:, c], color="tab:green", label="estimate error")
    ax1.fill_between(t, -sd2, sd2, color="tab:green", alpha=0.2, label="± 2σ from P")
    ax1.axhline(0, color="k", lw=0.8)
    ax1.set_xlabel("time (s)")
    ax1.set_ylabel(f"error ({unit})")
    ax1.legend(fontsize=8, ncol=3, loc="lower right")
    ax1.grid(alpha=0.3)
    fig.tight_layout()
    return fig


# ----------------------------------------------------------------------------------------------------------------
# Lab 11: tuning one filter on real data
# ----------------------------------------------------------------------------------------------------------------


def plot_tuning_sweep(sweep, chosen: float | None = None, figsize: tuple[float, ...] = (11, 3.6)) -> Figure:
    """Left: RMSE against the option's value, one line per trial (log axis), the chosen value marked.

    Right: the error over time at the chosen value (default: the first value), movement phase shaded.

    Parameters
    ----------
    sweep : fusionlab.bench.TuningSweep
        The runs to show.
    chosen : float, optional
        One of ``sweep.values`` (the nearest is taken).
    figsize : tuple of float, optional
        Figure size, inches.

    Returns
    -------
    matplotlib.figure.Figure
        Two axes.
    """
    j = 0 if chosen is None else int(np.argmin(np.abs(np.asarray(sweep.values) - float(chosen))))
    fig, (a1, a2) = plt.subplots(1, 2, figsize=figsize, constrained_layout=True, gridspec_kw={"width_ratios": [1, 1.6]})
    for i, name in enumerate(sweep.trials):
        (line,) = a1.plot(sweep.values, sweep.rmse_deg[i], "o-", label=name[:2] + " " + name[3:].replace("_", " "))
        a1.plot(sweep.values[j], sweep.rmse_deg[i, j], "o", ms=11, mfc="none", color=line.get_color())
        a2.plot(
            sweep.t[i],
            sweep.error_deg[i][j],
            lw=0.8,
            color=line.get_color(),
            label=f"{name[:2]}: RMSE {sweep.rmse_deg[i, j]:.2f}°",
        )
    a1.axvline(sweep.values[j], color="0.6", ls="--", lw=1)
    a1.set(
        xscale="log",
        xlabel=f"{sweep.option}",
        ylabel=f"{sweep.metric} RMSE (deg)",
        title=f"{sweep.estimator}: RMSE over the movement phase",
    )
    a1.legend(fontsize=8)
    a2.set(
        xlabel="time (s)",
        ylabel=f"{sweep.metric} error (deg)",
        title=f"{sweep.estimator}, {sweep.option} = {sweep.values[j]:g}",
    )
    a2.legend(fontsize=8, loc="upper left")
    return fig


# ----------------------------------------------------------------------------------------------------------------
# Lab 11: a first look at a real trial
# ----------------------------------------------------------------------------------------------------------------

from . import datasets as _datasets  # noqa: E402  (a data loader; plotting sits above it)

__all__ += ["shade_movement", "plot_trial"]


def shade_movement(ax: Axes, t: ArrayLike, movement: ArrayLike, color: str = "0.9") -> list[Rectangle]:
    """Shade, behind the data, each stretch of samples that ``movement`` marks (the phase the metrics score).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axis to shade; its x axis is time.
    t : array_like, shape (N,)
        Time of each sample, s.
    movement : array_like of bool, shape (N,)
        True on the samples of the movement phase.
    color : str, optional
        Shade colour (default light grey).

    Returns
    -------
    list of matplotlib.patches.Rectangle
        One span per stretch, each with gid ``'movement'``, from the first to the last sample of the stretch.
    """
    t = validate.array(t, "t")
    m = np.asarray(movement)
    if m.dtype != bool:
        raise ValueError(f"movement must be a boolean array; got dtype {m.dtype}")
    if t.ndim != 1 or m.shape != t.shape:
        raise ValueError(f"t and movement must both have shape (N,); got {t.shape} and {m.shape}")
    edges = np.flatnonzero(np.diff(np.r_[0, m.astype(int), 0]))  # starts and (one past) ends of each stretch
    return [ax.axvspan(t[a], t[b - 1], color=color, zorder=0, gid="movement") for a, b in zip(edges[::2], edges[1::2])]


def plot_trial(trial: _datasets.BroadTrial, title: str, step: int = 3) -> Figure:
    """The raw data of one BROAD trial in four stacked panels: gyro (deg/s), accelerometer (m/s²), magnetometer
    (µT) and the optical reference as Euler angles (deg, ENU), the movement phase shaded in each.

    Parameters
    ----------
    trial : datasets.BroadTrial
        The trial (or a slice of it).
    title : str
        The figure's title: what the reader should see in it.
    step : int, optional
        Draw every ``step``-th sample (default 3: enough for the eye at BROAD's 286 Hz).

    Returns
    -------
    matplotlib.figure.Figure
        Four axes sharing the time axis; the reference is NaN (a gap) where the markers were lost.
    """
    if not isinstance(trial, _datasets.BroadTrial):
        raise ValueError(f"trial must be a datasets.BroadTrial (from datasets.load_trial); got {type(trial).__name__}")
    if not isinstance(title, str):
        raise ValueError(f"title must be a string; got {type(title).__name__}")
    step = validate.count(step, "step", minimum=1)
    ref_euler = np.full((len(trial), 3), np.nan)
    ok = ~np.isnan(trial.quat_ref[:, 0])
    ref_euler[ok] = rotations.quat_to_euler(trial.quat_ref[ok])
    t = trial.t
    fig, axes = plt.subplots(4, 1, figsize=(11, 10), sharex=True, constrained_layout=True)
    for ax, y, label in zip(
        axes,
        (np.degrees(trial.gyr), trial.acc, trial.mag, np.degrees(ref_euler)),
        ("gyro (deg/s)", "acc (m/s²)", "mag (µT)", "reference (deg)"),
    ):
        shade_movement(ax, t, trial.movement)
        names = ("roll", "pitch", "yaw (ENU)") if label.startswith("ref") else ("x", "y", "z")
        for k in range(3):
            ax.plot(t[::step], y[::step, k], lw=0.7, label=names[k])
        ax.set_ylabel(label)
        ax.legend(loc="upper right", ncol=3, fontsize=8)
    axes[0].set_title(title)
    axes[-1].set_xlabel("time (s)")
    return fig


# ----------------------------------------------------------------------------------------------------------------
# Lab 08: the Earth-rate line of the rotating accelerometer and the FIR band-pass that finds it
# ----------------------------------------------------------------------------------------------------------------

from . import northfinder as _nf  # noqa: E402  (a seed-method module; plotting sits above it)

__all__ += ["plot_earth_rate_line", "plot_bandpass"]

_RECORD_KEYS = ("t", "acc", "theta", "A_c", "f_r", "fs")


def _record(rec):
    """A north-finder record (``northfinder.synthetic_record``) with the keys these figures read."""
    if not isinstance(rec, dict) or any(k not in rec for k in _RECORD_KEYS):
        have = sorted(rec) if isinstance(rec, dict) else type(rec).__name__
        raise ValueError(
            f"rec must be a record of northfinder.synthetic_record, with keys {', '.join(_RECORD_KEYS)}; got {have}"
        )
    return rec


def plot_earth_rate_line(rec: dict, heading: float, title: str, t_max: float = 0.9, f_max: float = 90.0) -> Figure:
    """The rotating accelerometer's record against the Earth-rate line it hides (left, the first ``t_max`` s) and
    the record's amplitude spectrum with the line marked (right).

    Parameters
    ----------
    rec : dict
        A record of :func:`fusionlab.northfinder.synthetic_record` (``t``, ``acc``, ``theta``, ``A_c``, ``f_r``,
        ``fs``).
    heading : float
        The true heading, rad: the line drawn is ``A_c·cos(θ + heading)``.
    title : str
        The figure's title: what the reader should see in it.
    t_max : float, optional
        Seconds of record shown on the left (default 0.9, three turns at 200 rpm).
    f_max : float, optional
        Highest frequency shown on the right, Hz (default 90).

    Returns
    -------
    matplotlib.figure.Figure
        Two axes, in µg; the spectrum is ``2|rfft(x)|/N`` of the record less its mean (a sinusoid of amplitude
        A shows as A).
    """
    rec = _record(rec)
    heading = validate.scalar(validate.angles_rad(heading, "heading"), "heading")
    t_max, f_max = validate.positive(t_max, "t_max"), validate.positive(f_max, "f_max")
    if not isinstance(title, str):
        raise ValueError(f"title must be a string; got {type(title).__name__}")
    t, A_c, f_r = rec["t"], rec["A_c"], rec["f_r"]
    x = rec["acc"] - rec["acc"].mean()
    spec = 2 * np.abs(np.fft.rfft(x)) / len(x)
    freq = np.fft.rfftfreq(len(x), 1 / rec["fs"])
    fig, axs = plt.subplots(1, 2, figsize=(10, 3.4))
    sl = t < t_max
    axs[0].plot(t[sl], x[sl] / _nf.UG, lw=0.8, label="record − mean")
    axs[0].plot(
        t[sl], A_c * np.cos(rec["theta"][sl] + heading) / _nf.UG, "k", lw=1.5, label="Earth-rate line", gid="line"
    )
    axs[0].set_xlabel("time (s)")
    axs[0].set_ylabel("acceleration (µg)")
    axs[0].legend(fontsize=8)
    axs[0].grid(alpha=0.3)
    band = freq < f_max
    axs[1].semilogy(freq[band], spec[band] / _nf.UG, lw=0.7, gid="spectrum")
    axs[1].plot(f_r, A_c / _nf.UG, "rv", label=f"Earth-rate line, {A_c / _nf.UG:.1f} µg")
    axs[1].set_xlim(0, f_max)
    axs[1].set_ylim(1e-3, 2e3)
    axs[1].set_xlabel("frequency (Hz)")
    axs[1].set_ylabel("amplitude (µg)")
    axs[1].legend(fontsize=8)
    axs[1].grid(alpha=0.3)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def plot_bandpass(
    rec: dict,
    taps: dict[int, ArrayLike],
    title: str,
    shown: int | None = None,
    f_max: float = 45.0,
    t_max: float = 12.0,
) -> Figure:
    """FIR band-pass filters around the spin rate: their gains with the drive harmonics dotted (left), and one of
    them run causally on the raw record, filling up before the line appears (right).

    Parameters
    ----------
    rec : dict
        A record of :func:`fusionlab.northfinder.synthetic_record`.
    taps : dict of int to array_like
        Filter order -> its ``order + 1`` taps (:func:`fusionlab.northfinder.bandpass_firls`).
    title : str
        The figure's title: what the reader should see in it.
    shown : int, optional
        The order run on the record (default: the largest).
    f_max : float, optional
        Highest frequency of the gain plot, Hz (default 45).
    t_max : float, optional
        Seconds of filtered record shown (default 12).

    Returns
    -------
    matplotlib.figure.Figure
        Two axes: gain (dB) against frequency, one line per order; the filtered record (µg), no mean removed.
    """
    from scipy.signal import freqz, lfilter

    rec = _record(rec)
    if not isinstance(taps, dict) or not taps:
        raise ValueError(f"taps must be a non-empty dict of order -> taps; got {type(taps).__name__}")
    taps = {m: validate.array(b, f"taps[{m}]") for m, b in taps.items()}
    shown = max(taps) if shown is None else shown
    if shown not in taps:
        raise ValueError(f"shown must be one of the orders in taps ({', '.join(map(str, taps))}); got {shown!r}")
    f_max, t_max = validate.positive(f_max, "f_max"), validate.positive(t_max, "t_max")
    if not isinstance(title, str):
        raise ValueError(f"title must be a string; got {type(title).__name__}")
    fs, f_r = rec["fs"], rec["f_r"]
    fig, axs = plt.subplots(1, 2, figsize=(10, 3.4))
    fgrid = np.linspace(0, f_max, 1500)
    for m, b in taps.items():
        _, h = freqz(b, worN=fgrid, fs=fs)
        axs[0].plot(fgrid, 20 * np.log10(np.abs(h) + 1e-12), lw=1, label=f"order {m}", gid=f"order {m}")
    for k in (k for k in _nf.HARMONICS if k * f_r < f_max):
        axs[0].axvline(k * f_r, color="0.7", lw=0.8, ls=":")
    axs[0].set_xlim(0, f_max)
    axs[0].set_ylim(-140, 10)
    axs[0].set_xlabel("frequency (Hz)")
    axs[0].set_ylabel("gain (dB)")
    axs[0].legend(fontsize=8)
    axs[0].grid(alpha=0.3)
    axs[0].set_title("firls band-pass (dotted: harmonics)", fontsize=10)
    first = rec["t"] < t_max
    y_causal = lfilter(taps[shown], 1.0, rec["acc"][first])  # raw record, no mean removal: the start-up
    axs[1].plot(rec["t"][first], y_causal / _nf.UG, lw=0.6, gid="filtered")
    axs[1].set_ylim(-200, 200)
    axs[1].set_xlim(0, t_max)
    axs[1].set_xlabel("time (s)")
    axs[1].set_ylabel("filtered (µg)")
    axs[1].grid(alpha=0.3)
    axs[1].set_title(f"order {shown}, causal, raw record", fontsize=10)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


# ----------------------------------------------------------------------------------------------------------------
# Lab 12: what each sensor error looks like
# ----------------------------------------------------------------------------------------------------------------

__all__ += ["plot_error_signatures"]


def plot_error_signatures(
    clouds: dict[str, tuple[ArrayLike, ArrayLike]], t: ArrayLike, angles: dict[str, ArrayLike], title: str
) -> Figure:
    """Sensor errors by their marks: one panel per point cloud (x-y projection of an ideal and a measured triad,
    equal axes), and a last panel of integrated gyro angles against time.

    Parameters
    ----------
    clouds : dict of str to (array_like, array_like)
        Panel label -> (ideal, measured), each of shape (N, 3) (m/s² or µT); at most five panels, row by row.
    t : array_like, shape (M,)
        Time of the gyro angles, s.
    angles : dict of str to array_like
        Label -> integrated angle of shape (M,), degrees.
    title : str
        The figure's title: what the reader should see in it.

    Returns
    -------
    matplotlib.figure.Figure
        A 2 x 3 grid: the clouds first, the angles in the last panel.
    """
    if not isinstance(clouds, dict) or not 1 <= len(clouds) <= 5:
        raise ValueError(
            f"clouds must be a dict of 1 to 5 label -> (ideal, measured) pairs; got "
            f"{len(clouds) if isinstance(clouds, dict) else type(clouds).__name__}"
        )
    pairs = {}
    for name, pair in clouds.items():
        if not isinstance(pair, (tuple, list)) or len(pair) != 2:
            raise ValueError(f"clouds[{name!r}] must be a pair (ideal, measured); got {type(pair).__name__}")
        pairs[name] = (
            validate.vectors(pair[0], f"clouds[{name!r}] ideal"),
            validate.vectors(pair[1], f"clouds[{name!r}] measured"),
        )
    t = validate.array(t, "t")
    if t.ndim != 1:
        raise ValueError(f"t must have shape (M,); got {t.shape}")
    if not isinstance(angles, dict):
        raise ValueError(f"angles must be a dict of label -> angle (deg); got {type(angles).__name__}")
    angles = {k: validate.array(v, f"angles[{k!r}]") for k, v in angles.items()}
    for k, v in angles.items():
        if v.shape != t.shape:
            raise ValueError(f"angles[{k!r}] must have the shape of t {t.shape}; got {v.shape}")
    if not isinstance(title, str):
        raise ValueError(f"title must be a string; got {type(title).__name__}")
    fig, axes = plt.subplots(2, 3, figsize=(11, 7), constrained_layout=True)
    for ax, (name, (ideal, data)) in zip(axes.flat, pairs.items()):
        ax.plot(ideal[:, 0], ideal[:, 1], ".", ms=2, color="0.7", label="ideal")
        ax.plot(data[:, 0], data[:, 1], ".", ms=2, label=name)
        ax.set_aspect("equal")
        ax.legend(fontsize=7, loc="upper right")
        ax.set_xlabel("x (m/s² or µT)")
        ax.set_ylabel("y")
    for ax in axes.flat[len(pairs) : 5]:
        ax.set_axis_off()
    for label, angle in angles.items():
        axes[1, 2].plot(t, angle, label=label)
    axes[1, 2].set_xlabel("time (s)")
    axes[1, 2].set_ylabel("integrated angle (°)")
    axes[1, 2].legend(fontsize=7)
    fig.suptitle(title)
    return fig


# ----------------------------------------------------------------------------------------------------------------
# Lab 04: the eCompass weights against a growing disturbance
# ----------------------------------------------------------------------------------------------------------------

__all__ += ["plot_disturbance_sweeps"]


def plot_disturbance_sweeps(sweeps: dict[str, tuple[ArrayLike, ArrayLike, ArrayLike, ArrayLike]], title: str) -> Figure:
    """Tilt error of a weighted and of an equal-weight estimate, and the weight ``α_g`` the weighted one gave the
    accelerometer, as one disturbance grows: one panel per disturbance, ``α_g`` on a right-hand axis.

    Parameters
    ----------
    sweeps : dict of str to tuple of four array_like
        x-axis label (the disturbance and its unit) -> ``(grid, alpha_g, tilt_weighted, tilt_equal)``, each of
        shape (K,): the disturbance sizes, the weight (0-1) and the two tilt errors (deg) at each size.
    title : str
        The figure's title: what the reader should see in it.

    Returns
    -------
    matplotlib.figure.Figure
        One axis per sweep and its twin (``α_g``, 0-1.05).
    """
    if not isinstance(sweeps, dict) or not sweeps:
        raise ValueError(
            f"sweeps must be a non-empty dict of label -> (grid, alpha_g, tilt_weighted, tilt_equal); "
            f"got {type(sweeps).__name__}"
        )
    checked = {}
    for label, sweep in sweeps.items():
        if not isinstance(sweep, (tuple, list)) or len(sweep) != 4:
            raise ValueError(
                f"sweeps[{label!r}] must be (grid, alpha_g, tilt_weighted, tilt_equal); got {type(sweep).__name__}"
            )
        parts = [validate.array(a, f"sweeps[{label!r}][{k}]") for k, a in enumerate(sweep)]
        if any(p.ndim != 1 or p.shape != parts[0].shape for p in parts):
            raise ValueError(
                f"sweeps[{label!r}] must hold four arrays of one shape (K,); got {[p.shape for p in parts]}"
            )
        checked[label] = parts
    if not isinstance(title, str):
        raise ValueError(f"title must be a string; got {type(title).__name__}")
    fig, axs = plt.subplots(1, len(checked), figsize=(4.5 * len(checked), 3.3), squeeze=False)
    for ax, (label, (grid, alpha_g, tilt_w, tilt_eq)) in zip(axs[0], checked.items()):
        ax.plot(grid, tilt_w, label="tilt error, note's weights", gid="weighted")
        ax.plot(grid, tilt_eq, color="0.6", label="tilt error, equal weights", gid="equal")
        ax2 = ax.twinx()
        ax2.plot(grid, alpha_g, "k:", label="α_g", gid="alpha_g")
        ax2.set_ylabel("α_g")
        ax2.set_ylim(0, 1.05)
        ax.set_xlabel(label)
        ax.set_ylabel("tilt error (deg)")
        ax.grid(alpha=0.3)
    axs[0, 0].legend(loc="upper left", fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    return fig
