"""``python -m grading.capstone fetch`` and ``python -m grading.capstone grade ...``: :func:`grading.capstone.main`
(in :mod:`grading.capstone.command`)."""

from __future__ import annotations

import sys

from .command import main


if __name__ == "__main__":
    sys.exit(main())
