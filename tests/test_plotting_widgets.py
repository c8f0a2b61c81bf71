"""Figures (fusionlab.plotting) and the Euler viewer widget (fusionlab.widgets), without a front end."""

import matplotlib

matplotlib.use("Agg")

import ipywidgets as W  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from fusionlab import falling_body, plotting, rotations, widgets  # noqa: E402

EULER = np.radians([10.0, -10.0, 40.0])


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def _tip(ax, gid):
    """End point (display coords) of the arrow shaft with this gid."""
    lines = [ln for ln in ax.get_lines() if ln.get_gid() == gid]
    assert len(lines) == 1, f"expected one line with gid {gid!r}, found {len(lines)}"
    return np.array(lines[0].get_data_3d())[:, -1]


def test_ned_to_display_draws_down_down_without_mirroring():
    north, east, down = np.eye(3)
    np.testing.assert_allclose(plotting.ned_to_display(north), [0, 1, 0])
    np.testing.assert_allclose(plotting.ned_to_display(east), [1, 0, 0])
    np.testing.assert_allclose(plotting.ned_to_display(down), [0, 0, -1])  # Down points down on screen
    assert np.linalg.det(plotting.NED_TO_DISPLAY) == pytest.approx(1.0)  # a rotation, not a mirror


def test_plot_euler_frames_has_four_panels_with_the_right_arrows():
    fig = plotting.plot_euler_frames(EULER)
    assert isinstance(fig, Figure)
    assert len(fig.axes) == 4
    F = plotting.euler_frames(EULER)
    C_bn = rotations.euler_to_dcm(EULER)
    np.testing.assert_allclose(F["B"], C_bn, atol=1e-15)
    body = fig.axes[3]
    for k, name in enumerate("xyz"):
        np.testing.assert_allclose(_tip(body, f"B:{name}"), plotting.ned_to_display(C_bn[:, k]), atol=1e-12)
    # the yaw panel: v1 x axis is (cos ψ, sin ψ, 0) in NED, and the inertial frame is drawn grey beside it
    np.testing.assert_allclose(
        _tip(fig.axes[1], "v1:x"), plotting.ned_to_display([np.cos(EULER[2]), np.sin(EULER[2]), 0]), atol=1e-12
    )
    grey = [ln for ln in fig.axes[1].get_lines() if ln.get_gid() == "I:x"][0]
    red = [ln for ln in body.get_lines() if ln.get_gid() == "B:x"][0]
    assert matplotlib.colors.to_hex(grey.get_color()) == matplotlib.colors.to_hex(plotting.GREY)
    assert matplotlib.colors.to_hex(red.get_color()) == matplotlib.colors.to_hex("tab:red")


def test_plot_euler_frames_titles_and_labels_state_the_angles():
    fig = plotting.plot_euler_frames(EULER)
    titles = [ax.get_title() for ax in fig.axes]
    assert "yaw ψ = 40°" in titles[1] and "$z_{I}$" in titles[1]
    assert "pitch θ = -10°" in titles[2] and "$y_{v1}$" in titles[2]
    assert "roll φ = 10°" in titles[3] and "$x_{v2}$" in titles[3]
    for ax in fig.axes:
        assert (ax.get_xlabel(), ax.get_ylabel(), ax.get_zlabel()) == ("East", "North", "Up (= -Down)")
    assert len([ln for ln in fig.axes[3].get_lines() if ln.get_gid() == "aircraft"]) == 1  # aircraft in body panel
    assert not any(ln.get_gid() == "aircraft" for ax in fig.axes[:3] for ln in ax.get_lines())


def test_plot_euler_frames_single_panel():
    fig = plotting.plot_euler_frames(EULER, stages=False)
    assert len(fig.axes) == 1
    np.testing.assert_allclose(
        _tip(fig.axes[0], "B:z"), plotting.ned_to_display(rotations.euler_to_dcm(EULER)[:, 2]), atol=1e-12
    )


@pytest.mark.parametrize(
    "bad, match",
    [
        ([0.1, 0.2], r"euler must have shape"),
        ([[0.1, 0.2, 0.3]], r"euler must have shape \(3,\)"),
        ([0.1, np.nan, 0.3], r"euler must hold finite"),
        ([10.0, -10.0, 40.0], r"euler must be in radians"),  # degrees passed by mistake
    ],
)
def test_plot_euler_frames_rejects_bad_euler(bad, match):
    with pytest.raises(ValueError, match=match):
        plotting.plot_euler_frames(bad)


def test_draw_triad_rejects_non_3x3():
    fig = plt.figure()
    ax = plotting.setup_ned_axes(fig.add_subplot(projection="3d"))
    with pytest.raises(ValueError, match="C must have shape"):
        plotting.draw_triad(ax, np.eye(4))


@pytest.mark.parametrize("pitch_deg", [90.0, -90.0])
def test_plot_gimbal_lock_two_pairs_same_triad(pitch_deg):
    roll, yaw = np.radians(30.0), np.radians(50.0)
    fig = plotting.plot_gimbal_lock(roll, yaw, np.radians(pitch_deg))
    assert isinstance(fig, Figure) and len(fig.axes) == 3
    A = np.array([_tip(fig.axes[0], f"A:{n}") for n in "xyz"])
    B = np.array([_tip(fig.axes[1], f"B:{n}") for n in "xyz"])
    np.testing.assert_allclose(A, B, atol=1e-12)
    combo = "φ − ψ" if pitch_deg > 0 else "φ + ψ"
    expected = "-20°" if pitch_deg > 0 else "80°"  # 30 - 50 and 30 + 50
    assert combo in fig.get_suptitle() and "same attitude" in fig.get_suptitle()
    assert f"{combo} = {expected}" in fig.axes[0].get_title()
    assert f"{combo} = {expected}" in fig.axes[1].get_title()
    assert "ψ = 0°" in fig.axes[1].get_title()  # pair B is what dcm_to_euler reports


def test_plot_gimbal_lock_away_from_lock_pairs_differ():
    fig = plotting.plot_gimbal_lock(np.radians(30.0), np.radians(50.0), np.radians(60.0))
    A, B = _tip(fig.axes[0], "A:x"), _tip(fig.axes[1], "B:x")
    assert np.max(np.abs(A - B)) > 0.1
    assert "different attitudes" in fig.get_suptitle()


def test_plot_gimbal_lock_rejects_array_roll():
    with pytest.raises(ValueError, match="roll must be a scalar"):
        plotting.plot_gimbal_lock([0.1, 0.2], 0.3)


def test_viewer_state_at_lock_recovers_only_roll_minus_yaw():
    st = widgets.viewer_state(25.0, -10.0, 70.0, lock=True)
    np.testing.assert_allclose(st["euler_deg"], [25.0, 90.0, 70.0])
    roll_b, pitch_b, yaw_b = st["euler_readback_deg"]
    assert yaw_b == 0.0
    assert pitch_b == pytest.approx(90.0, abs=1e-9)
    assert roll_b == pytest.approx(25.0 - 70.0, abs=1e-9)
    np.testing.assert_allclose(st["C_bn"], rotations.euler_to_dcm(np.radians([25.0, 90.0, 70.0])), atol=1e-15)
    assert st["det"] == pytest.approx(1.0, abs=1e-12)
    assert "φ − ψ = -45.0°" in st["html"]


def test_viewer_state_away_from_lock_reads_back_the_sliders():
    st = widgets.viewer_state(10.0, -10.0, 40.0, lock=False)
    np.testing.assert_allclose(st["euler_readback_deg"], [10.0, -10.0, 40.0], atol=1e-9)
    C = st["C_bn"]
    assert f"{C[0, 0]:.3f}" in st["html"] and f"{C[2, 1]:.3f}" in st["html"]
    assert "Gimbal lock" not in st["html"]


def _leaves(box):
    return [w for c in box.children for w in (_leaves(c) if isinstance(c, W.Box) else [c])]


def _controls(box):
    by_desc = {c.description: c for c in _leaves(box) if getattr(c, "description", "")}
    html = [c for c in box.children if isinstance(c, W.HTML)]
    return by_desc["ψ yaw (°)"], by_desc["θ pitch (°)"], by_desc["gimbal lock (θ = 90°)"], html[0]


def test_euler_viewer_builds_headless_and_lock_pins_pitch():
    box = widgets.euler_viewer()
    assert isinstance(box, W.VBox)
    yaw, pitch, lock, readout = _controls(box)
    sliders = [c for c in _leaves(box) if isinstance(c, W.FloatSlider)]
    assert len(sliders) == 3 and all(s.continuous_update and s.step == 1 for s in sliders)
    assert (yaw.min, yaw.max, pitch.min, pitch.max) == (-180, 180, -90, 90)
    assert readout.value == widgets.viewer_state(10, -10, 40, False)["html"]
    [out] = [c for c in box.children if isinstance(c, W.Output)]
    assert len(out.outputs) == 1 and "image/png" in out.outputs[0]["data"]  # drawn once, headless

    lock.value = True
    assert pitch.disabled and pitch.value == 90.0
    assert readout.value == widgets.viewer_state(10, 90, 40, True)["html"]
    assert "φ − ψ = -30.0°" in readout.value
    lock.value = False
    assert not pitch.disabled and pitch.value == -10.0  # the pitch before the lock comes back


def test_euler_viewer_typed_angle_moves_the_slider_and_redraws():
    box = widgets.euler_viewer()
    yaw_row, pitch_row = box.children[0], box.children[1]
    slider, typed = pitch_row.children
    assert isinstance(typed, W.BoundedFloatText) and (typed.min, typed.max, typed.step) == (-90, 90, 0.1)
    [out] = [c for c in box.children if isinstance(c, W.Output)]
    before = out.outputs[0]["data"]["image/png"]
    typed.value = 89.5
    assert slider.value == 89.5
    assert _controls(box)[3].value == widgets.viewer_state(10, 89.5, 40, False)["html"]
    assert out.outputs[0]["data"]["image/png"] != before
    yaw_row.children[0].value = 120.0
    assert yaw_row.children[1].value == 120.0
    box_lock = _controls(box)[2]
    box_lock.value = True
    assert typed.disabled and typed.value == 90.0


def test_euler_viewer_yaw_slider_updates_readout():
    box = widgets.euler_viewer()
    yaw, _, _, readout = _controls(box)
    before = readout.value
    yaw.value = -30.0
    assert readout.value != before
    assert readout.value == widgets.viewer_state(10, -10, -30, False)["html"]


# ----------------------------------------------------------------------------------------------------------------
# Lab 11: shade_movement and plot_trial
# ----------------------------------------------------------------------------------------------------------------


def _small_trial():
    """A 2 s BroadTrial of constant rotation, movement from 0.5 s to 1.0 s and 1.5 s to the end, reference lost
    on 10 samples."""
    from fusionlab import datasets

    fs, n = 100.0, 200
    gyr = np.tile([0.0, 0.0, 0.5], (n, 1))
    q = rotations.integrate_gyro_quat([1.0, 0, 0, 0], gyr, 1 / fs)[1:]
    q[20:30] = np.nan
    movement = np.zeros(n, bool)
    movement[50:100] = movement[150:] = True
    return datasets._make_trial(
        "00_test", (), "", fs, gyr, np.tile([0.0, 0, 9.81], (n, 1)), np.tile([20.0, 0, -40.0], (n, 1)), q, movement
    )


def test_shade_movement_shades_each_stretch_from_its_first_to_its_last_sample():
    tr = _small_trial()
    fig, ax = plt.subplots()
    spans = plotting.shade_movement(ax, tr.t, tr.movement)
    assert [s.get_gid() for s in spans] == ["movement", "movement"]
    xs = [[round(s.get_x(), 6), round(s.get_x() + s.get_width(), 6)] for s in spans]
    assert xs == [[0.5, 0.99], [1.5, 1.99]]
    plt.close(fig)


@pytest.mark.parametrize(
    "t, movement, match",
    [
        (np.arange(5.0), np.ones(5), "movement must be a boolean array; got dtype float64"),
        (np.arange(5.0), np.ones(4, bool), r"t and movement must both have shape \(N,\); got \(5,\) and \(4,\)"),
        (np.array([0.0, np.nan]), np.ones(2, bool), "t must hold finite numbers"),
    ],
)
def test_shade_movement_rejects_bad_input(t, movement, match):
    fig, ax = plt.subplots()
    with pytest.raises(ValueError, match=match):
        plotting.shade_movement(ax, t, movement)
    plt.close(fig)


def test_plot_trial_draws_four_shaded_panels_with_the_reference_as_euler_angles():
    tr = _small_trial()
    fig = plotting.plot_trial(tr, "the finding", step=1)
    axes = fig.axes
    assert [ax.get_ylabel() for ax in axes] == ["gyro (deg/s)", "acc (m/s²)", "mag (µT)", "reference (deg)"]
    assert axes[0].get_title() == "the finding" and axes[-1].get_xlabel() == "time (s)"
    assert all(sum(p.get_gid() == "movement" for p in ax.patches) == 2 for ax in axes)
    gz = axes[0].get_lines()[2].get_ydata()
    np.testing.assert_allclose(gz, np.degrees(0.5))  # deg/s
    yaw = axes[3].get_lines()[2].get_ydata()
    assert np.isnan(yaw[20:30]).all()  # the lost reference is a gap
    np.testing.assert_allclose(yaw[100], np.degrees(0.5 * 1.01), rtol=1e-9)  # yaw after 101 steps of 0.01 s
    assert len(plotting.plot_trial(tr, "x").axes[0].get_lines()[0].get_xdata()) == 67  # every 3rd sample
    plt.close("all")


def test_plot_trial_rejects_what_is_not_a_trial():
    with pytest.raises(ValueError, match="trial must be a datasets.BroadTrial"):
        plotting.plot_trial({"t": np.arange(3)}, "title")
    with pytest.raises(ValueError, match="title must be a string; got NoneType"):
        plotting.plot_trial(_small_trial(), None)
    with pytest.raises(ValueError, match="step must be an integer >= 1; got 0"):
        plotting.plot_trial(_small_trial(), "title", step=0)


# ----------------------------------------------------------------------------------------------------------------
# Lab 08: plot_earth_rate_line and plot_bandpass
# ----------------------------------------------------------------------------------------------------------------


def _nf_record():
    from fusionlab import northfinder as nf

    return nf.synthetic_record(np.radians(-42.0), duration=3.0, noise=0.0, harmonics={}, seed=1)  # 10 turns


def test_plot_earth_rate_line_shows_the_line_at_its_amplitude_in_the_spectrum():
    from fusionlab import northfinder as nf

    rec = _nf_record()  # no harmonics, no noise: the record is the line
    fig = plotting.plot_earth_rate_line(rec, np.radians(-42.0), "the finding")
    left, right = fig.axes
    assert fig._suptitle.get_text() == "the finding"
    line = next(ln for ln in left.get_lines() if ln.get_gid() == "line")
    np.testing.assert_allclose(line.get_ydata(), left.get_lines()[0].get_ydata(), atol=0.05 * rec["A_c"] / nf.UG)
    spec = next(ln for ln in right.get_lines() if ln.get_gid() == "spectrum")
    f, a = spec.get_xdata(), spec.get_ydata()
    assert f[np.argmax(a)] == pytest.approx(rec["f_r"], abs=1e-9)  # 3 s: f_r is bin 10
    assert a.max() == pytest.approx(rec["A_c"] / nf.UG, rel=0.1)
    assert f.max() < 90 and left.get_lines()[0].get_xdata().max() < 0.9
    plt.close(fig)


def test_plot_bandpass_draws_one_gain_per_order_and_the_chosen_order_on_the_record():
    from fusionlab import northfinder as nf

    rec = _nf_record()
    taps = {m: nf.bandpass_firls(m, rec["fs"], rec["f_r"]) for m in (100, 400)}
    fig = plotting.plot_bandpass(rec, taps, "the finding", t_max=2.5)
    gains, out = fig.axes
    assert [ln.get_gid() for ln in gains.get_lines() if ln.get_gid()] == ["order 100", "order 400"]
    f = gains.get_lines()[1].get_xdata()
    g400 = gains.get_lines()[1].get_ydata()
    assert g400[np.argmin(np.abs(f - rec["f_r"]))] == pytest.approx(0.0, abs=1.0)  # passes the line
    assert out.get_title() == "order 400, causal, raw record" and fig._suptitle.get_text() == "the finding"
    assert out.get_lines()[0].get_xdata().max() < 2.5
    plt.close(fig)


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda rec: plotting.plot_earth_rate_line({"t": 1}, 0.1, "x"), "rec must be a record of northfinder"),
        (lambda rec: plotting.plot_earth_rate_line(rec, 42.0, "x"), "heading must be in radians"),
        (lambda rec: plotting.plot_earth_rate_line(rec, 0.1, None), "title must be a string"),
        (lambda rec: plotting.plot_bandpass(rec, {}, "x"), "taps must be a non-empty dict"),
        (
            lambda rec: plotting.plot_bandpass(rec, {10: np.ones(11)}, "x", shown=20),
            r"shown must be one of the orders in taps \(10\); got 20",
        ),
        (lambda rec: plotting.plot_bandpass(rec, {10: [np.nan] * 11}, "x"), r"taps\[10\] must hold finite numbers"),
        (lambda rec: plotting.plot_bandpass(rec, {10: np.ones(11)}, "x", f_max=0.0), "f_max must be a positive"),
    ],
)
def test_lab08_figures_reject_bad_input(call, match):
    with pytest.raises(ValueError, match=match):
        call(_nf_record())
    plt.close("all")


# ----------------------------------------------------------------------------------------------------------------
# Lab 12: plot_error_signatures
# ----------------------------------------------------------------------------------------------------------------


def test_plot_error_signatures_puts_each_cloud_in_a_panel_and_the_angles_last():
    ideal = np.array([[1.0, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0]])
    clouds = {"bias": (ideal, ideal + [0.5, 0, 0]), "scale": (ideal, ideal * [1.2, 1, 1])}
    t = np.arange(5.0)
    fig = plotting.plot_error_signatures(clouds, t, {"ramp": 2 * t}, "the finding")
    axes = fig.axes
    assert fig._suptitle.get_text() == "the finding"
    np.testing.assert_array_equal(axes[0].get_lines()[1].get_xdata(), [1.5, 0.5, -0.5, 0.5])
    np.testing.assert_array_equal(axes[1].get_lines()[1].get_xdata(), [1.2, 0, -1.2, 0])
    assert [ln.get_label() for ln in axes[1].get_lines()] == ["ideal", "scale"]
    assert not axes[2].axison and not axes[4].axison  # unused cloud panels are switched off
    np.testing.assert_array_equal(axes[5].get_lines()[0].get_ydata(), 2 * t)
    assert axes[5].get_ylabel() == "integrated angle (°)"
    plt.close(fig)


@pytest.mark.parametrize(
    "args, match",
    [
        (({}, np.arange(3.0), {}, "x"), "clouds must be a dict of 1 to 5"),
        (({"a": np.ones((3, 3))}, np.arange(3.0), {}, "x"), r"clouds\['a'\] must be a pair \(ideal, measured\)"),
        (({"a": (np.ones((3, 3)), np.ones((3, 2)))}, np.arange(3.0), {}, "x"), r"clouds\['a'\] measured must have"),
        (
            ({"a": (np.ones((3, 3)), np.ones((3, 3)))}, np.arange(3.0), {"r": np.ones(4)}, "x"),
            r"angles\['r'\] must have the shape of t \(3,\); got \(4,\)",
        ),
        (({"a": (np.ones((3, 3)), np.ones((3, 3)))}, np.arange(3.0), {}, 3), "title must be a string"),
    ],
)
def test_plot_error_signatures_rejects_bad_input(args, match):
    with pytest.raises(ValueError, match=match):
        plotting.plot_error_signatures(*args)
    plt.close("all")


# ----------------------------------------------------------------------------------------------------------------
# Lab 04: plot_disturbance_sweeps
# ----------------------------------------------------------------------------------------------------------------


def test_plot_disturbance_sweeps_draws_both_errors_and_the_weight_per_disturbance():
    g = np.linspace(0.0, 1.0, 5)
    sweeps = {"acceleration (g)": (g, 1 - g / 2, 10 * g, 5 * g), "magnet (µT)": (100 * g, np.ones(5), 0 * g, 3 * g)}
    fig = plotting.plot_disturbance_sweeps(sweeps, "the finding")
    assert len(fig.axes) == 4 and tuple(fig.get_size_inches()) == (9.0, 3.3)
    a0, a1, t0, t1 = fig.axes  # twins are added after the panels
    assert fig._suptitle.get_text() == "the finding" and a1.get_xlabel() == "magnet (µT)"
    lines = {ln.get_gid(): ln for ln in a0.get_lines()}
    np.testing.assert_array_equal(lines["weighted"].get_ydata(), 10 * g)
    np.testing.assert_array_equal(lines["equal"].get_ydata(), 5 * g)
    np.testing.assert_array_equal(t0.get_lines()[0].get_ydata(), 1 - g / 2)
    assert t1.get_ylim() == (0.0, 1.05)
    plt.close(fig)


@pytest.mark.parametrize(
    "sweeps, title, match",
    [
        ({}, "x", "sweeps must be a non-empty dict"),
        ({"a": (np.ones(3),) * 3}, "x", r"sweeps\['a'\] must be \(grid, alpha_g, tilt_weighted, tilt_equal\)"),
        ({"a": (np.ones(3), np.ones(3), np.ones(4), np.ones(3))}, "x", r"sweeps\['a'\] must hold four arrays of one"),
        ({"a": (np.ones(3), np.ones(3), [np.nan] * 3, np.ones(3))}, "x", r"sweeps\['a'\]\[2\] must hold finite"),
        ({"a": (np.ones(3),) * 4}, None, "title must be a string"),
    ],
)
def test_plot_disturbance_sweeps_rejects_bad_input(sweeps, title, match):
    with pytest.raises(ValueError, match=match):
        plotting.plot_disturbance_sweeps(sweeps, title)
    plt.close("all")


# ---------------------------------------------------------------- lab 02: the Gaussian product and the filter run
def test_gaussian_product_explorer_builds_headless_and_updates():
    box = widgets.gaussian_product_explorer(0.0, 4.0, 3.0, 1.0)
    sliders = [c for c in box.children if isinstance(c, W.FloatSlider)]
    readout = [c for c in box.children if isinstance(c, W.HTML)][0]
    assert len(sliders) == 4 and not any(s.continuous_update for s in sliders)
    assert readout.value == widgets.gaussian_product_state(0, 4, 3, 1)["html"]
    assert "μ = 2.40, σ² = 0.80" in readout.value
    sliders[3].value = 4.0  # equal variances: halfway
    assert "μ = 1.50, σ² = 2.00" in readout.value
    st = widgets.gaussian_product_state(0, 4, 3, 4)
    assert st["K"] == pytest.approx(0.5)


def test_lab02_figures_draw_what_they_claim():
    fig = plotting.plot_gaussian_product(0.0, 4.0, 3.0, 1.0)
    prod = [ln for ln in fig.axes[0].get_lines() if ln.get_gid() == "product"][0]
    xs, ys = prod.get_data()
    assert xs[np.argmax(ys)] == pytest.approx(2.4, abs=0.03)
    truth, z = falling_body.simulate_falling_body(1, seed=2)
    run = falling_body.ThesisKF.falling_body().run(z[0])
    fig = plotting.plot_kf_run(np.arange(1, 200) * 0.01, truth[0, 1:], z[0], run["x"], run["P"])
    assert len(fig.axes) == 2 and fig.axes[1].get_xlabel() == "time (s)"
    with pytest.raises(ValueError, match="P must have shape"):
        plotting.plot_kf_run(np.arange(199) * 0.01, truth[0, 1:], z[0], run["x"], run["P"][:10])
