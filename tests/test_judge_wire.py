"""What crosses between the student's box and the judge is data only, read strictly (``grading/box.py``,
``grading/client.py``): the codec's round trip, and what the judge refuses to build."""

from __future__ import annotations

import gc
import json
import re
import time
import types

import numpy as np
import pytest
import sympy as sp

from grading import box, client


@pytest.mark.parametrize(
    "value",
    [
        1,
        -2.5,
        float("nan"),
        float("inf"),
        1 + 2j,
        True,
        None,
        "text",
        [1, [2.0, "x"]],
        (1, (2, 3)),
        {"a": [1, 2], "b": (3.0,)},
        np.arange(6.0).reshape(2, 3),
        np.array([1, 2], dtype=np.int32),
        np.array([True, False]),
        np.array([[1 + 1j]]),
        np.float64(3.5),
        np.zeros((0, 3)),
    ],
)
def test_plain_data_survives_the_round_trip_exactly(value):
    back = box.decode(json.loads(json.dumps(box.encode(value), allow_nan=False)))
    if isinstance(value, np.ndarray) or isinstance(value, np.generic):
        assert np.asarray(back).dtype == np.asarray(value).dtype and np.array_equal(back, value)
    elif isinstance(value, float) and value != value:
        assert back != back
    else:
        assert back == value and type(back) is type(value)


@pytest.mark.parametrize(
    "value, why",
    [
        (np.array(["a"]), "only arrays of numbers"),
        (np.array([object()]), "only arrays of numbers"),
        ({1: 2}, "keys are not all strings"),
        (lambda x: x, "only numbers"),
        (open, "only numbers"),
    ],
)
def test_anything_else_is_refused_by_the_sender(value, why):
    with pytest.raises(box.WireError, match=why):
        box.encode(value)


@pytest.mark.parametrize(
    "message, why",
    [
        ({"__ndarray__": "|O", "shape": [1], "data": ""}, "a dtype that is not a plain number"),
        ({"__ndarray__": "<f8", "shape": [3], "data": "AAAAAAAAAAA="}, "bytes for shape"),
        ({"__ndarray__": "<f8", "shape": [-1], "data": ""}, "bad array shape"),
        ({"__pickle__": "gASV"}, "unknown kind"),
        ({"__object__": "os:system", "state": {}}, "an object where numbers were expected"),
        ({"__sympy__": "Symbol('x')"}, "a sympy expression where numbers were expected"),
    ],
)
def test_the_reader_refuses_what_is_not_plain_data(message, why):
    with pytest.raises(box.WireError, match=why):
        box.decode(message)


def _gadget_names():
    """Every class the old decoder would have rebuilt in the judge: ``fusionlab.<module>:<chain>`` for each class
    reachable from a library module in one or two attribute steps (``fusionlab.datasets:tempfile._TemporaryFileCloser``,
    ``fusionlab.accel_tilt:np.lib._datasource.DataSource`` is three: a sample of those too)."""
    import importlib
    import pkgutil

    import fusionlab

    names = set()
    for info in pkgutil.iter_modules(fusionlab.__path__):
        module = importlib.import_module(f"fusionlab.{info.name}")
        for a in dir(module):
            obj = getattr(module, a, None)
            if isinstance(obj, type):
                names.add(f"{module.__name__}:{a}")
            elif isinstance(obj, types.ModuleType):
                for b in dir(obj):
                    if isinstance(getattr(obj, b, None), type):
                        names.add(f"{module.__name__}:{a}.{b}")
    return sorted(
        names
        | {
            "fusionlab.accel_tilt:np.lib._datasource.DataSource",
            "fusionlab.datasets:tempfile._TemporaryFileCloser",
            "fusionlab.freescale:Kalman9",
        }
    )


def test_no_class_is_rebuilt_from_a_name_the_sender_wrote(tmp_path):
    canary = tmp_path / "classmate.ipynb"
    canary.write_text("{}")
    names = _gadget_names()
    assert len(names) > 500 and "fusionlab.datasets:tempfile._TemporaryFileCloser" in names
    state = {"name": str(canary), "file": None, "delete": True, "_destpath": str(tmp_path), "close_called": False}
    for name in names:
        for key in (name, name.replace(":", "."), name.split(":")[-1]):
            message = {"__object__": key, "state": {"__dict__": {k: box.encode(v) for k, v in state.items()}}}
            with pytest.raises(box.WireError, match="does not cross the pipe|an unknown kind"):
                box.decode(json.loads(json.dumps(message)), objects=True, make_sympy=client.sympy_trusted)
    gc.collect()
    assert canary.read_text() == "{}", "no __del__ of a gadget ran in this process"


def test_a_library_object_crosses_as_its_fields_and_comes_back_as_its_own_class():
    from fusionlab import freescale

    kf = freescale.Kalman9("Android")
    kf.q = np.array([0.5, 0.5, 0.5, 0.5])
    kf.delta_deg = 61.5
    back = box.decode(json.loads(json.dumps(box.encode(kf))), objects=True)
    assert type(back) is freescale.Kalman9 and type(back.tuning) is freescale.Tuning
    assert back.frame == "Android" and back.delta_deg == 61.5 and np.array_equal(back.q, kf.q)
    assert set(vars(back)) == set(vars(kf))
    with pytest.raises(box.WireError, match="an object where numbers were expected"):
        box.decode(json.loads(json.dumps(box.encode(kf))))


def _kalman9_message(**change):
    from fusionlab import freescale

    message = json.loads(json.dumps(box.encode(freescale.Kalman9())))
    message["state"].update({k: box.encode(v) for k, v in change.items()})
    return message


@pytest.mark.parametrize(
    "change, why",
    [
        ({"q": np.zeros(5)}, "field q of a library object: expected an array of shape \\(4,\\)"),
        ({"q": "1, 0, 0, 0"}, "field q of a library object: expected an array"),
        ({"delta_deg": True}, "field delta_deg of a library object: expected a number"),
        ({"frame": "x" * 1000}, "field frame of a library object: expected a str"),
        ({"__class__": 1}, "whose fields are not its class's"),
        ({"tuning": {"a": 1}}, "field tuning of a library object: expected a Tuning"),
    ],
)
def test_a_library_object_with_other_fields_or_kinds_is_refused(change, why):
    with pytest.raises(box.WireError, match=why):
        box.decode(_kalman9_message(**change), objects=True)


def test_the_library_refuses_a_tuning_it_would_not_build():
    from fusionlab import freescale

    message = json.loads(json.dumps(box.encode(freescale.Tuning())))
    message["state"]["Q_wb"] = -1.0
    with pytest.raises(box.WireError, match="the library refuses"):
        box.decode(message, objects=True)
    message["state"]["Q_wb"], message["state"]["oversample"] = 0.5, 8.5
    with pytest.raises(box.WireError, match="field oversample of a library object: expected an integer"):
        box.decode(message, objects=True)


def _random_message(rng, depth=0):
    """A random JSON value shaped like the protocol's: plain values, the codec's tagged dicts with good and bad
    contents, library-object messages under every key the codec knows and many it does not."""
    keys = [
        "__float__",
        "__complex__",
        "__ndarray__",
        "shape",
        "data",
        "__tuple__",
        "__dict__",
        "__sympy__",
        "__object__",
        "state",
        "__reduce__",
        "__class__",
        "x",
    ]
    leaf = [
        None,
        True,
        3,
        -(2**70),
        2.5,
        "nan",
        "inf",
        "",
        "AAAAAAAAAAA=",
        "<f8",
        "|O",
        "os:system",
        "freescale.Kalman9",
        "freescale.Tuning",
        "fusionlab.freescale:Kalman9",
        "Symbol('x')",
        "__import__('os')",
        [],
        {},
    ]
    r = rng.random()
    if depth > 4 or r < 0.35:
        return leaf[rng.integers(len(leaf))]
    if r < 0.55:
        return [_random_message(rng, depth + 1) for _ in range(rng.integers(0, 4))]
    if r < 0.75:
        chosen = rng.choice(keys, size=rng.integers(1, 4), replace=False)
        return {str(k): _random_message(rng, depth + 1) for k in chosen}
    from fusionlab import freescale

    samples = [freescale.Kalman9(), freescale.Tuning(), 1 + 2j, np.arange(3.0), (1, "a"), {"k": [1.0]}]
    good = json.loads(json.dumps(box.encode(samples[rng.integers(len(samples))])))
    if isinstance(good, dict) and "state" in good and rng.random() < 0.7:
        field_ = rng.choice(sorted(good["state"]))
        good["state"][str(field_)] = _random_message(rng, depth + 1)
    return good


def _only_data(value):
    from fusionlab import freescale

    if value is None or isinstance(value, (bool, int, float, complex, str)):
        return True
    if isinstance(value, np.ndarray):
        return value.dtype.kind in box.NUMERIC_KINDS
    if isinstance(value, (list, tuple)):
        return all(_only_data(v) for v in value)
    if isinstance(value, dict):
        return all(isinstance(k, str) and _only_data(v) for k, v in value.items())
    if type(value) in (freescale.Kalman9, freescale.Tuning):
        return all(_only_data(v) for v in box.wire_fields(value).values())
    return isinstance(value, (sp.Basic, sp.MatrixBase))


def test_random_messages_decode_to_data_or_are_refused():
    rng = np.random.default_rng(37)
    decoded = refused = 0
    for _ in range(5000):
        message = _random_message(rng)
        try:
            value = box.decode(message, objects=True, make_sympy=client.sympy_trusted)
        except box.WireError:
            refused += 1
            continue
        decoded += 1
        assert _only_data(value), message
    assert decoded > 1000 and refused > 500, (decoded, refused)


def test_the_judge_rebuilds_sympy_without_parsing_any_text_the_student_sent():
    a, b = sp.symbols("a b", real=True)
    for expr in (sp.Matrix([[a**2 * b, 3 * a], [sp.Rational(1, 2), sp.Float(0.25)]]), sp.sin(a) * sp.exp(b) - 1):
        assert client.sympy_trusted(sp.srepr(expr)) == expr
    for evil in (
        'Matrix(\'__import__("os").system("echo pwned")\')',
        "Symbol('x; import os')",
        "Float('1e1;2')",
        "Function('f')(Symbol('x'))",
        "Integer(2).__class__",
        "Lambda(Symbol('x'), Symbol('x'))",
    ):
        with pytest.raises(box.WireError):
            client.sympy_trusted(evil)


def test_a_dtype_that_is_not_a_plain_number_is_refused_before_numpy_reads_it():
    flood = {"__ndarray__": "i1," * 2_000_000, "shape": [1], "data": ""}
    t0 = time.perf_counter()
    with pytest.raises(box.WireError, match="not a plain number"):
        box.decode(flood)
    assert time.perf_counter() - t0 < 0.5
    for text in ("<M8[ns]", "V8", "<U2", "O", "(2,)f8", "f8,i4", "<f8 "):
        with pytest.raises(box.WireError):
            box.decode({"__ndarray__": text, "shape": [0], "data": ""})


@pytest.mark.parametrize(
    "text",
    [
        "Pow(Integer(2), Integer(4000000000))",  # 36 characters; gigabytes once evaluated
        "Pow(Pow(Pow(Integer(999999), Integer(100)), Integer(100)), Integer(100))",
        "Mul(" + ", ".join(["Pow(Integer(999999), Integer(3000))"] * 50) + ")",
        "Float('1.5', 1000000)",
        "Float('1.5', precision=10000000)",
        "Integer(10000001)",
        "Add(" + ", ".join(["Symbol('x')"] * 30_000) + ")",
        # a 12 x 12 integer matrix to the 9000th: built unevaluated, then minutes of the judge's time in np.asarray
        "Pow(ImmutableDenseMatrix(["
        + ", ".join("[" + ", ".join(f"Integer({(i * 12 + j) % 7 + 1})" for j in range(12)) + "]" for i in range(12))
        + "]), Integer(9000))",
        "exp(ImmutableDenseMatrix([[Integer(1), Integer(2)], [Integer(3), Integer(4)]]))",
        "Pow(Mul(Integer(2), ImmutableDenseMatrix([[Integer(1), Integer(2)], [Integer(3), Integer(4)]])), Integer(50))",
    ],
)
def test_a_sympy_expression_that_would_cost_the_judge_is_refused_before_sympy_builds_it(text):
    t0 = time.perf_counter()
    with pytest.raises(box.WireError, match="sympy"):
        client.sympy_trusted(text)
    assert time.perf_counter() - t0 < 1.0


def test_honest_sympy_answers_stay_within_the_bounds():
    a, b = sp.symbols("a b", real=True)
    for expr in (
        a**-3 + b ** sp.Rational(1, 2),
        sp.Float("0.1", 30) * a,
        sp.Matrix(3, 3, lambda i, j: a**i * b**j),
        sp.Pow(a, 60) * 999_999,
    ):
        assert client.sympy_trusted(sp.srepr(expr)) == expr


def test_a_hidden_verdict_names_only_the_courses_own_errors_word_for_word():
    from grading import boxlib, judge

    class Lab:
        lab = "02_kalman_falling_body"
        forbidden = {"ex3_tests": {"fusionlab.kalman:predict"}}

    stub = "NotImplementedError: " + boxlib.STUB_MESSAGE.format(name="kalman.predict")
    assert judge.known_error(stub, Lab, "ex3_tests") == judge.FORBIDDEN_CALLED
    assert "kalman" not in judge.FORBIDDEN_CALLED, "which of the forbidden functions was called is the student's choice"
    said = {
        judge.known_error(f"NotImplementedError: {e} not attempted yet", Lab, "ex3_tests")
        for e in ("exercise 3", "exercise 1", "exercise 58b", "question 25e", "exercise 41i")
    }
    assert said == {judge.NOT_ATTEMPTED} and not re.search(r"\d", judge.NOT_ATTEMPTED), (
        "an unfinished exercise is named without its number, which the student's code could choose"
    )
    absent = f"ImportError: ahrs is not available while the lab is graded: {boxlib.WHY_HIDDEN}"
    assert judge.known_error(absent, Lab, "ex3_tests") == judge.HIDDEN_IMPORTED and "ahrs" not in judge.HIDDEN_IMPORTED
    only_here = f"ImportError: sympy is not available while the lab is graded: {boxlib.WHY_HIDDEN}"  # kept for Lab 07
    assert judge.known_error(only_here, Lab, "ex3_tests") == judge.HIDDEN_IMPORTED
    for forged in (
        stub + " 5.8138",
        "NotImplementedError: exercise 3 not attempted yet (P = 5.81)",
        stub.replace("kalman.predict", "kalman.update"),
        "ValueError: exercise 3 not attempted yet",
    ):
        assert judge.known_error(forged, Lab, "ex3_tests") is None, forged
