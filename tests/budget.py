"""How long the fast tests and each lab take, against their budgets: ``make test-budget`` (not a test).

Times on a shared machine vary, so no test asserts them; this script measures and reports instead, so that a slow
new test or a slow new cell is seen at once:

* ``suite``: the fast tier exactly as ``make test`` runs it (its pytest command, read from ``make -n test``),
  ``--repeat`` times; prints each run's wall time, their median, the load average before and after, and the median
  against ``--budget`` (default 8 minutes; venv creation is not included: a fresh clone times it, see the README);
* ``labs``: every solution notebook run top to bottom in a fresh kernel (kernel start included, as a student's
  Restart & Run All), ``--repeat`` times each; prints each lab's median against ``--lab-budget`` (default 12 s).

Exit status 1 if a median is over its budget, so ``make test-budget`` can stand in a scheduled job.

    python tests/budget.py labs --repeat 3
    python tests/budget.py suite --repeat 3
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LABS = sorted(p.name for p in (ROOT / "solutions").iterdir() if p.is_dir() and p.name[:2].isdigit())


def load():
    """The 1-minute load average, as text (the machine's other work is part of every figure)."""
    return f"{os.getloadavg()[0]:.2f}"


def fast_tier_commands():
    """The pytest commands of ``make test``, as make prints them (``make -n``), so this never drifts from it."""
    out = subprocess.run(
        ["make", "-n", "--no-print-directory", "test"], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout
    return [line for line in out.splitlines() if "-m pytest" in line]


def time_suite(repeat, budget):
    commands = fast_tier_commands()
    times = []
    for k in range(repeat):
        before = load()
        start = time.perf_counter()
        for command in commands:
            run = subprocess.run(command, shell=True, cwd=ROOT, capture_output=True, text=True)
            if run.returncode != 0:
                sys.exit(
                    f"run {k + 1}: the fast tier failed, so its time means nothing:\n{command}\n"
                    f"{run.stdout[-3000:]}{run.stderr[-2000:]}"
                )
        times.append(time.perf_counter() - start)
        print(f"run {k + 1}: {times[-1]:6.1f} s   (load average {before} before, {load()} after)", flush=True)
    median = statistics.median(times)
    print(
        f"fast tier: median {median:.1f} s of {repeat} against a budget of {budget:.0f} s "
        f"({'within' if median <= budget else 'OVER'})"
    )
    return median <= budget


def run_lab(lab):
    """Wall time of one Run All of ``lab``'s solution in a fresh kernel, kernel start included."""
    import nbformat
    from fusionlab.execute import run_notebook

    nb = nbformat.read(ROOT / "solutions" / lab / f"{lab}.ipynb", as_version=4)
    start = time.perf_counter()
    run_notebook(
        nb, cwd=ROOT / "solutions" / lab, timeout=120, allow_errors=False, stderr=subprocess.DEVNULL
    )  # the kernel's own warnings are not news here
    return time.perf_counter() - start


def time_labs(repeat, budget, labs):
    over = []
    print(f"{'lab':26s} {'median':>7s}  runs (s)          load", flush=True)
    for lab in labs:
        before = load()
        times = [run_lab(lab) for _ in range(repeat)]
        median = statistics.median(times)
        if median > budget:
            over.append(lab)
        print(
            f"{lab:26s} {median:6.1f}s  {' '.join(f'{t:5.1f}' for t in times):17s} {before}"
            f"{'   OVER ' + format(budget, '.0f') + ' s' if median > budget else ''}",
            flush=True,
        )
    print(
        f"{len(labs) - len(over)} of {len(labs)} labs within {budget:.0f} s"
        + (f"; over: {', '.join(over)}" if over else "")
    )
    return not over


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("what", choices=["suite", "labs", "both"])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--budget", type=float, default=480.0, help="seconds for the fast tier (default 480)")
    parser.add_argument("--lab-budget", type=float, default=12.0, help="seconds per lab (default 12)")
    parser.add_argument("--labs", nargs="*", default=LABS, help="labs to time (default: all)")
    args = parser.parse_args(argv)
    if args.repeat < 1:
        parser.error("--repeat must be 1 or more")
    ok = True
    if args.what in ("labs", "both"):
        ok &= time_labs(args.repeat, args.lab_budget, args.labs)
    if args.what in ("suite", "both"):
        ok &= time_suite(args.repeat, args.budget)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
