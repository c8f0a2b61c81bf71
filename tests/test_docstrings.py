"""Docstrings that documentation tools can parse: numpydoc's validator on every public object of the modules below.

Every flat module of the library is in DOCUMENTED. For each public function and class it defines (a name without a
leading underscore whose ``__module__`` is the module), and each public method or property of such a class, numpydoc's
validator must report none of:

* PR01 -- a parameter of the signature has no entry under Parameters;
* PR02 -- an entry names a parameter the signature does not have (often ``a, b : ...`` written as one entry);
* PR04 -- an entry has no type (``x : array_like, shape (N, 3)``);
* PR10 -- ``x: type`` without the space before the colon (the whole line is then read as the name);
* GL08 -- no docstring at all;
* GL07 -- the sections are out of numpydoc's order.

A warning numpydoc raises while it parses (``Unknown section 'Return'``, a section title it does not know, which
it then drops from the parsed docstring) is a failure too.
"""

from __future__ import annotations

import importlib
import inspect
import warnings
from pathlib import Path

import pytest
from numpydoc import validate as numpydoc_validate  # pinned in environment.txt: a missing one fails, not skips

# Every flat module of the library: a new module is held to the same rule from its first commit. (The checks
# package speaks to students, not to documentation tools, and is not listed.)
DOCUMENTED = sorted(
    p.stem for p in (Path(__file__).resolve().parents[1] / "lib" / "fusionlab").glob("*.py") if p.stem != "__init__"
)
assert len(DOCUMENTED) >= 19, f"no library found beside {__file__}"


CODES = ("PR01", "PR02", "PR04", "PR10", "GL08", "GL07")


def public_objects(module_name: str) -> list[str]:
    """Dotted names of the public functions and classes defined in ``fusionlab.<module_name>``, with the public
    methods and properties of those classes."""
    module = importlib.import_module(f"fusionlab.{module_name}")
    names = []
    for name, obj in vars(module).items():
        if name.startswith("_") or not (inspect.isfunction(obj) or inspect.isclass(obj)):
            continue
        if getattr(obj, "__module__", None) != module.__name__:  # imported from elsewhere: checked there
            continue
        names.append(f"{module.__name__}.{name}")
        if inspect.isclass(obj):
            for attr, member in vars(obj).items():
                if attr.startswith("_"):
                    continue
                if isinstance(member, (staticmethod, classmethod)):
                    member = member.__func__
                if inspect.isfunction(member) or isinstance(member, property):
                    names.append(f"{module.__name__}.{name}.{attr}")
    return names


def docstring_problems(dotted_name: str) -> list[str]:
    """One line ``object: CODE message`` per numpydoc error in CODES and per warning raised while parsing."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        report = numpydoc_validate.validate(dotted_name)
    problems = [f"{dotted_name}: {code} {message}" for code, message in report["errors"] if code in CODES]
    problems += [f"{dotted_name}: WARNING {w.message}" for w in caught]
    return problems


@pytest.mark.parametrize("module_name", DOCUMENTED)
def test_public_docstrings_parse_with_one_typed_entry_per_parameter(module_name):
    names = public_objects(module_name)
    assert names, f"fusionlab.{module_name} defines no public function or class: is the module name right?"
    problems = [p for name in names for p in docstring_problems(name)]
    if problems:
        pytest.fail(
            f"{len(problems)} docstring problem(s) in fusionlab.{module_name} ({len(names)} public objects):"
            "\n  " + "\n  ".join(problems),
            pytrace=False,
        )


def test_the_validator_reports_what_this_test_relies_on():
    """The codes above are the validator's own: a docstring with each fault is reported under its code."""
    import types

    def faulty(accel, gyro, dt):
        """Integrate the gyro.

        Parameters
        ----------
        accel, gyro : array_like
            Combined entry.
        dt: float
            No space before the colon.
        stale
            An entry for a parameter that is not there.

        Returns
        -------
        ndarray
        """

    def silent(x):
        pass

    def unknown_section(x):
        """Return x.

        Parameters
        ----------
        x : float
            The value.

        Return
        ------
        float
        """

    scratch = types.ModuleType("fusionlab_docstring_scratch")
    for fn in (faulty, silent, unknown_section):
        fn.__module__ = scratch.__name__
        setattr(scratch, fn.__name__, fn)
    import sys

    sys.modules[scratch.__name__] = scratch
    try:
        found = {
            name: docstring_problems(f"{scratch.__name__}.{name}") for name in ("faulty", "silent", "unknown_section")
        }
    finally:
        del sys.modules[scratch.__name__]
    codes = {name: sorted({p.split(": ", 1)[1].split(" ", 1)[0] for p in ps}) for name, ps in found.items()}
    assert codes["faulty"] == ["PR01", "PR02", "PR04", "PR10"], found["faulty"]
    assert codes["silent"] == ["GL08"], found["silent"]
    assert codes["unknown_section"] == ["GL07", "WARNING"], found["unknown_section"]  # also read as misplaced
    assert any("WARNING Unknown section Return" in p for p in found["unknown_section"]), found["unknown_section"]
