"""The student's side of grading: runs a submission's cells, then answers calls with plain data.

This file is started by :mod:`grading.judge` inside the grading sandbox (:mod:`grading.sandbox`) as
``python box.py``, with a pipe on its standard input and output.  Everything in this process belongs to the student:
it holds the student's code, a copy of the library in which the reference answers of the lab are stubs, and no test,
no expected value and no score.  It only

1. reads the program (the cells to run, in order) as one JSON line and runs each cell, reporting ``start`` and
   ``done`` (with the error's type and message) so that the judge can time each cell and stop a stuck one;
2. answers requests, one JSON line each: ``describe`` (is a name a function, a value, or missing), ``call`` (call a
   function of the notebook with arguments, return the result and the new state of library objects passed in),
   ``get`` (a value).

What goes over the pipe is data only -- numbers, strings, lists, dicts with string keys, numpy arrays of numbers,
sympy expressions as ``srepr`` text, and the few library types of :data:`WIRE_TYPES` as their fields -- encoded by
:func:`encode` and read back by :func:`decode`, which refuses anything else.  No class is ever looked up by a name
the other side wrote: a library object travels under a key of :data:`WIRE_TYPES` and is rebuilt from a fresh
instance of that class, field by field, each field checked against the fresh instance's (same names, same kinds,
arrays of the same shape), so a ``__del__`` or ``__reduce__`` of the student's choosing has nothing to run in.  The
judge decodes replies with the same function and its own strict policy: no pickle, no code, and (:mod:`grading.judge`)
no reply longer than it reads before parsing.

Standard output and error of the student's code go to a capped file in the sandbox's private ``/tmp``: nothing a
cell prints can reach the judge.
"""

from __future__ import annotations

import base64
import json
import math
import os
import re
import sys
from typing import BinaryIO, TYPE_CHECKING

if TYPE_CHECKING:
    from collections.abc import Callable

NUMERIC_KINDS = "biufc"  # bool, int, unsigned, float, complex: the only array dtypes that cross the pipe
MAX_DEPTH = 12
MAX_ITEMS = 1_000_000  # list items per message
MAX_TEXT = 1_000_000  # characters of one string
DTYPE = re.compile(r"[<>|=]?[biufc][0-9]{1,2}")  # an array's dtype as encode writes it ('<f8', '|b1')
OUTPUT_BYTES = 1_000_000  # what the student's code may print (kept in the sandbox, never read by the judge)


class WireError(ValueError):
    """A message that is not plain data of the kinds this protocol allows."""


#: The library's own types that cross the pipe (a test passes one to the student's function, which changes it):
#: key on the wire -> ``module:class``. Each is rebuilt from a fresh instance of its class, field by field; nothing
#: else of the library (and nothing named by the sender) is ever rebuilt.
WIRE_TYPES = {
    "freescale.Tuning": "fusionlab.freescale:Tuning",  # a field of Kalman9
    "freescale.Kalman9": "fusionlab.freescale:Kalman9",  # Lab 05, exercise 6: my_step(kf, ...) changes kf
}
MAX_WIRE_TEXT = 200  # characters of a text field of a library object (a frame name)


_CLASSES = {}


def _wire_classes():
    """``{key: class}`` of :data:`WIRE_TYPES`, imported once, by this module's own names."""
    import importlib

    if not _CLASSES:
        for key, where in WIRE_TYPES.items():
            module, _, name = where.partition(":")
            _CLASSES[key] = getattr(importlib.import_module(module), name)
    return _CLASSES


def wire_key(value: object) -> str | None:
    """The :data:`WIRE_TYPES` key of ``value``'s exact class, or None (a subclass or a look-alike is not one)."""
    module = type(value).__module__ or ""
    if module.split(".")[0] != "fusionlab":
        return None
    return next((key for key, cls in _wire_classes().items() if type(value) is cls), None)


def wire_fields(value: object) -> dict:
    """``{name: value}`` of the fields a library object of :data:`WIRE_TYPES` travels with."""
    import dataclasses

    if dataclasses.is_dataclass(value):
        return {f.name: getattr(value, f.name) for f in dataclasses.fields(value)}
    return dict(vars(value))


def _same_kind(name, value, template):
    """``value`` for the field ``name`` whose fresh value is ``template``: of the same kind, or WireError."""
    import numpy as np

    if isinstance(template, np.ndarray):
        if not isinstance(value, np.ndarray) or value.shape != template.shape or value.dtype.kind not in "biuf":
            raise WireError(f"field {name} of a library object: expected an array of shape {template.shape}")
        return value.astype(template.dtype)
    if isinstance(template, bool) or template is None or isinstance(template, str):
        if type(value) is not type(template) or (isinstance(value, str) and len(value) > MAX_WIRE_TEXT):
            raise WireError(f"field {name} of a library object: expected a {type(template).__name__}")
        return value
    if isinstance(template, (int, float)):
        kinds = int if isinstance(template, int) else (int, float)
        if isinstance(value, bool) or not isinstance(value, kinds):
            expected = "an integer" if kinds is int else "a number"
            raise WireError(f"field {name} of a library object: expected {expected}")
        return type(template)(value)
    if wire_key(template) is not None:
        if type(value) is not type(template):
            raise WireError(f"field {name} of a library object: expected a {type(template).__name__}")
        return value
    raise WireError(f"field {name} of a library object cannot cross the pipe")


def rebuild(key: str, state: dict) -> object:
    """The library object of :data:`WIRE_TYPES` ``key`` with the fields ``state`` (decoded values), made from a fresh
    instance of its class: the same field names, each of the fresh value's kind. Raises WireError otherwise."""
    import dataclasses

    classes = _wire_classes()
    if key not in classes:
        raise WireError("an object of a type that does not cross the pipe")
    fresh = classes[key]()
    template = wire_fields(fresh)
    if set(state) != set(template):
        raise WireError(f"a {key} whose fields are not its class's")
    fields = {name: _same_kind(name, state[name], template[name]) for name in template}
    if dataclasses.is_dataclass(fresh):
        try:
            return dataclasses.replace(fresh, **fields)
        except (ValueError, TypeError) as exc:
            raise WireError(f"a {key} the library refuses ({exc})") from None
    update(fresh, fields)
    return fresh


def update(obj: object, fields: dict) -> None:
    """Set the fields of the library object ``obj`` (a :data:`WIRE_TYPES` instance, not a frozen dataclass)."""
    for name, value in fields.items():
        setattr(obj, name, value)


# ---------------------------------------------------------------------------------------------------------------
# The codec (shared by both sides: the judge imports these functions)
# ---------------------------------------------------------------------------------------------------------------


def _float(x):
    if math.isfinite(x):
        return x
    return {"__float__": "nan" if math.isnan(x) else ("inf" if x > 0 else "-inf")}


def encode(value: object, depth: int = 0, objects: bool = True):
    """``value`` as JSON-ready plain data; raises :class:`WireError` for anything else.

    The library objects of :data:`WIRE_TYPES` travel as their key and fields when ``objects`` is true; sympy
    expressions as their ``srepr`` text.
    """
    import numpy as np

    if depth > MAX_DEPTH:
        raise WireError("nested too deeply")
    if value is None or isinstance(value, (bool, str)):
        if isinstance(value, str) and len(value) > MAX_TEXT:
            raise WireError("a string longer than 1,000,000 characters")
        return value
    if isinstance(value, int) and not isinstance(value, bool):
        return value if abs(value) < 2**63 else _float(float(value))
    if isinstance(value, float):
        return _float(value)
    if isinstance(value, complex):
        return {"__complex__": [_float(value.real), _float(value.imag)]}
    if isinstance(value, np.generic) and not isinstance(value, np.ndarray):
        value = np.asarray(value)
    if isinstance(value, np.ndarray):
        if value.dtype.kind not in NUMERIC_KINDS:
            raise WireError(f"an array of {value.dtype} (only arrays of numbers are accepted)")
        arr = np.ascontiguousarray(value)
        if arr.dtype.byteorder == ">":
            arr = arr.astype(arr.dtype.newbyteorder("<"))
        return {
            "__ndarray__": arr.dtype.str,
            "shape": list(arr.shape),
            "data": base64.b64encode(arr.tobytes()).decode("ascii"),
        }
    if isinstance(value, (list, tuple)):
        if len(value) > MAX_ITEMS:
            raise WireError("a list of more than 1,000,000 items")
        items = [encode(v, depth + 1, objects) for v in value]
        return {"__tuple__": items} if isinstance(value, tuple) else items
    if isinstance(value, dict):
        if not all(isinstance(k, str) for k in value):
            raise WireError("a dict whose keys are not all strings")
        return {"__dict__": {k: encode(v, depth + 1, objects) for k, v in value.items()}}
    module = type(value).__module__ or ""
    if module.split(".")[0] == "sympy":
        import sympy

        if isinstance(value, (sympy.Basic, sympy.MatrixBase)):
            return {"__sympy__": sympy.srepr(value)}
    key = wire_key(value) if objects else None
    if key is not None:
        return {"__object__": key, "state": {k: encode(v, depth + 1, objects) for k, v in wire_fields(value).items()}}
    raise WireError(
        f"a {type(value).__name__} (only numbers, arrays of numbers, strings, lists, tuples and dicts are accepted)"
    )


def decode(data: object, *, objects: bool = False, make_sympy: Callable[[str], object] | None = None, depth: int = 0):
    """The value that :func:`encode` encoded, checked strictly (dtype, shape, size); raises :class:`WireError`.

    With ``objects`` true, the library objects of :data:`WIRE_TYPES` are rebuilt (:func:`rebuild`); ``make_sympy(text)``
    builds sympy expressions. Without them such values are refused.
    """
    import numpy as np

    if depth > MAX_DEPTH:
        raise WireError("nested too deeply")
    if data is None or isinstance(data, (bool, int, str)):
        return data
    if isinstance(data, float):
        return data
    if isinstance(data, list):
        return [decode(v, objects=objects, make_sympy=make_sympy, depth=depth + 1) for v in data]
    if not isinstance(data, dict) or len(data) not in (1, 2, 3):
        raise WireError("an unknown kind of value")
    sub = dict(objects=objects, make_sympy=make_sympy, depth=depth + 1)
    if set(data) == {"__float__"}:
        text = data["__float__"]
        if text not in ("nan", "inf", "-inf"):
            raise WireError("a bad float")
        return float(text)
    if set(data) == {"__complex__"}:
        if not isinstance(data["__complex__"], list) or len(data["__complex__"]) != 2:
            raise WireError("a bad complex number")
        re_, im = (decode(v, **sub) for v in data["__complex__"])
        if not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in (re_, im)):
            raise WireError("a bad complex number")
        return complex(re_, im)
    if set(data) == {"__ndarray__", "shape", "data"}:
        text = data["__ndarray__"]
        if not isinstance(text, str) or not DTYPE.fullmatch(text):  # checked before numpy parses it
            raise WireError("an array of a dtype that is not a plain number")
        try:
            dtype = np.dtype(text)
        except (TypeError, ValueError):
            raise WireError("an array of an unknown dtype") from None
        shape = data["shape"]
        if dtype.kind not in NUMERIC_KINDS or dtype.hasobject or dtype.fields is not None:
            raise WireError(f"an array of {dtype}")
        if (
            not isinstance(shape, list)
            or not all(isinstance(n, int) and not isinstance(n, bool) and n >= 0 for n in shape)
            or len(shape) > 32
        ):
            raise WireError("a bad array shape")
        if not isinstance(data["data"], str):
            raise WireError("array data that is not text")
        try:
            raw = base64.b64decode(data["data"], validate=True)
        except ValueError:
            raise WireError("array data that is not base64") from None
        if len(raw) != math.prod(shape) * dtype.itemsize:
            raise WireError(f"array data of {len(raw)} bytes for shape {tuple(shape)} of {dtype}")
        return np.frombuffer(raw, dtype=dtype).reshape(shape).copy()
    if set(data) == {"__tuple__"} and isinstance(data["__tuple__"], list):
        return tuple(decode(v, **sub) for v in data["__tuple__"])
    if set(data) == {"__dict__"} and isinstance(data["__dict__"], dict):
        return {str(k): decode(v, **sub) for k, v in data["__dict__"].items()}
    if set(data) == {"__sympy__"} and isinstance(data["__sympy__"], str):
        if make_sympy is None:
            raise WireError("a sympy expression where numbers were expected")
        return make_sympy(data["__sympy__"])
    if set(data) == {"__object__", "state"} and isinstance(data["state"], dict):
        if not objects:
            raise WireError("an object where numbers were expected")
        if not isinstance(data["__object__"], str) or data["__object__"] not in WIRE_TYPES:
            raise WireError("an object of a type that does not cross the pipe")
        state = {str(k): decode(v, **sub) for k, v in data["state"].items()}
        return rebuild(data["__object__"], state)
    raise WireError("an unknown kind of value")


# ---------------------------------------------------------------------------------------------------------------
# The runner (student side)
# ---------------------------------------------------------------------------------------------------------------


def _short(exc):
    text = f"{type(exc).__name__}: {exc}"
    return text if len(text) < 600 else text[:600] + " ..."


def _sympy_here(text):
    import sympy

    return eval(text, vars(sympy).copy())  # noqa: S307 -- in the student's own process, on the judge's own inputs


def run(requests: BinaryIO, replies: BinaryIO) -> None:
    """Run the program read from ``requests``, then answer requests until the pipe closes."""

    def send(message):
        replies.write((json.dumps(message, allow_nan=False) + "\n").encode())
        replies.flush()

    program = json.loads(requests.readline())
    from IPython.core.interactiveshell import InteractiveShell
    from traitlets.config import Config

    config = Config()
    config.HistoryManager.enabled = False  # history in memory: no database file, no file lock to take
    shell = InteractiveShell.instance(config=config)
    shell.display_pub.publish = lambda *a, **k: None  # rich outputs (figures, widgets) go nowhere
    for i, source in enumerate(program["cells"]):
        send({"cell": i, "state": "start"})
        try:
            result = shell.run_cell(source, store_history=False, silent=False)
            error = result.error_before_exec or result.error_in_exec
        except BaseException as exc:  # noqa: BLE001 -- a cell that escapes the shell is still only its own failure
            error = exc
        pyplot = sys.modules.get("matplotlib.pyplot")  # imported by the cells that plot (the backend: MPLBACKEND=Agg)
        if pyplot is not None:
            pyplot.close("all")
        send({"cell": i, "state": "done", "error": _short(error) if error is not None else None})
    send({"ready": True})
    ns = shell.user_ns

    for line in requests:
        try:
            req = json.loads(line)
            op = req["op"]
            if op == "describe":
                out = {}
                for name in req["names"]:
                    if name not in ns:
                        out[name] = {"kind": "missing"}
                    elif callable(ns[name]) and not isinstance(ns[name], type):
                        out[name] = {"kind": "function"}
                    else:
                        try:
                            out[name] = {"kind": "value", "value": encode(ns[name])}
                        except WireError as exc:
                            out[name] = {"kind": "unreadable", "error": str(exc)}
                send({"ok": True, "names": out})
            elif op == "call":
                args = decode(req["args"], objects=True, make_sympy=_sympy_here)
                kwargs = decode(req["kwargs"], objects=True, make_sympy=_sympy_here)
                try:
                    value = ns[req["name"]](*args, **kwargs)
                except BaseException as exc:  # noqa: BLE001 -- the student's error is the answer
                    send({"ok": False, "error": _short(exc)})
                    continue
                try:
                    send(
                        {
                            "ok": True,
                            "value": encode(value),
                            "objects": {str(i): encode(a) for i, a in enumerate(args) if wire_key(a)},
                        }
                    )
                except WireError as exc:
                    send({"ok": False, "error": f"your function returned {exc}"})
            else:
                send({"ok": False, "error": f"unknown request {op!r}"})
        except BaseException as exc:  # noqa: BLE001
            send({"ok": False, "error": _short(exc)})


def main() -> None:
    requests = os.fdopen(os.dup(0), "rb")
    replies = os.fdopen(os.dup(1), "wb")
    null = os.open(os.devnull, os.O_RDONLY)
    os.dup2(null, 0)
    out = os.open(
        os.path.join(os.environ.get("TMPDIR", "/tmp"), "box-output.txt"), os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600
    )
    os.dup2(out, 1)
    os.dup2(out, 2)
    sys.stdout = open(1, "w", buffering=1, closefd=False)
    sys.stderr = open(2, "w", buffering=1, closefd=False)
    run(requests, replies)


if __name__ == "__main__":
    main()
