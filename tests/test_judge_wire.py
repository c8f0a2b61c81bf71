"""What crosses between the student's box and the judge is data only, read strictly (``grading/box.py``,
``grading/judge.py``): the codec's round trip, and what the judge refuses to build."""
from __future__ import annotations

import json

import numpy as np
import pytest
import sympy as sp

from grading import box, judge


@pytest.mark.parametrize("value", [
    1, -2.5, float("nan"), float("inf"), 1 + 2j, True, None, "text", [1, [2.0, "x"]], (1, (2, 3)),
    {"a": [1, 2], "b": (3.0,)}, np.arange(6.0).reshape(2, 3), np.array([1, 2], dtype=np.int32),
    np.array([True, False]), np.array([[1 + 1j]]), np.float64(3.5), np.zeros((0, 3)),
])
def test_plain_data_survives_the_round_trip_exactly(value):
    back = box.decode(json.loads(json.dumps(box.encode(value), allow_nan=False)))
    if isinstance(value, np.ndarray) or isinstance(value, np.generic):
        assert np.asarray(back).dtype == np.asarray(value).dtype and np.array_equal(back, value)
    elif isinstance(value, float) and value != value:
        assert back != back
    else:
        assert back == value and type(back) is type(value)


@pytest.mark.parametrize("value, why", [
    (np.array(["a"]), "only arrays of numbers"), (np.array([object()]), "only arrays of numbers"),
    ({1: 2}, "keys are not all strings"), (lambda x: x, "only numbers"), (open, "only numbers"),
])
def test_anything_else_is_refused_by_the_sender(value, why):
    with pytest.raises(box.WireError, match=why):
        box.encode(value)


@pytest.mark.parametrize("message, why", [
    ({"__ndarray__": "|O", "shape": [1], "data": ""}, "array of object"),
    ({"__ndarray__": "<f8", "shape": [3], "data": "AAAAAAAAAAA="}, "bytes for shape"),
    ({"__ndarray__": "<f8", "shape": [-1], "data": ""}, "bad array shape"),
    ({"__pickle__": "gASV"}, "unknown kind"),
    ({"__object__": "os:system", "state": {}}, "an object where numbers were expected"),
    ({"__sympy__": "Symbol('x')"}, "a sympy expression where numbers were expected"),
])
def test_the_reader_refuses_what_is_not_plain_data(message, why):
    with pytest.raises(box.WireError, match=why):
        box.decode(message)


def test_library_objects_come_only_from_the_library():
    with pytest.raises(box.WireError, match="only the library's own objects"):
        box.library_object("subprocess:Popen", {})
    from fusionlab import freescale
    kf = freescale.Kalman9("NED")
    back = box.decode(json.loads(json.dumps(box.encode(kf))), make_object=box.library_object)
    assert type(back) is freescale.Kalman9 and np.array_equal(back.q, kf.q)


def test_the_judge_rebuilds_sympy_without_parsing_any_text_the_student_sent():
    a, b = sp.symbols("a b", real=True)
    for expr in (sp.Matrix([[a**2 * b, 3 * a], [sp.Rational(1, 2), sp.Float(0.25)]]), sp.sin(a) * sp.exp(b) - 1):
        assert judge._sympy_trusted(sp.srepr(expr)) == expr
    for evil in ("Matrix('__import__(\"os\").system(\"echo pwned\")')", "Symbol('x; import os')", "Float('1e1;2')",
                 "Function('f')(Symbol('x'))", "Integer(2).__class__", "Lambda(Symbol('x'), Symbol('x'))"):
        with pytest.raises(box.WireError):
            judge._sympy_trusted(evil)
