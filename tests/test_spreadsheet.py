"""The Lab 03 spreadsheet (data/lab03_fusion.xlsx): reproducible, and its live formulas equal the Python pipeline."""
import hashlib
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from fusionlab import correlation as co

DATA = Path(__file__).resolve().parents[1] / "data"
XLSX = DATA / "lab03_fusion.xlsx"


def _sha(path):
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def test_spreadsheet_regenerates_byte_identical(tmp_path):
    out = co.write_spreadsheet(co.parse_terminal_log(DATA / "lab03" / "motion.log"), tmp_path / "x.xlsx", 0.02)
    assert _sha(out) == _sha(XLSX)
    assert _sha(XLSX) in (DATA / "README.md").read_text()


def test_spreadsheet_holds_formulas_for_every_step():
    openpyxl = pytest.importorskip("openpyxl")
    ws = openpyxl.load_workbook(XLSX)["fusion"]
    assert ws["F3"].value == "=ATAN2(E3,D3)"                       # Excel order: the tilt (000 eq 5.5)
    assert ws["P3"].value == "=O3*H3+(1-O3)*(P2+L3)"               # (000 eq 5.17)
    assert [ws.cell(1, k).value[:2] for k in range(4, 18)] == ["a)", "a)", "b)", "c)", "d)", "e)", "f)", "g)", "h)",
                                                              "e'", "i)", "j)", "k)", "l)"]


def test_libreoffice_recalculation_equals_pipeline(tmp_path):
    soffice = shutil.which("soffice") or shutil.which("libreoffice")
    if soffice is None:
        pytest.skip("LibreOffice not found: install it (Debian: apt-get install libreoffice-calc-nogui) "
                    "to recalculate data/lab03_fusion.xlsx headless")
    openpyxl = pytest.importorskip("openpyxl")
    subprocess.run([soffice, "--headless", "--norestore", f"-env:UserInstallation=file://{tmp_path}/profile",
                    "--convert-to", "xlsx", "--outdir", str(tmp_path / "out"), str(XLSX)],
                   check=True, capture_output=True, timeout=180)
    ws = openpyxl.load_workbook(tmp_path / "out" / XLSX.name, data_only=True)["fusion"]
    df = co.pipeline(co.parse_terminal_log(DATA / "lab03" / "motion.log"), 0.02)
    rows = range(2, len(df) + 2)
    for col, name in co.SHEET_TO_PIPELINE.items():
        cells = np.array([ws[f"{col}{r}"].value for r in rows], dtype=float)
        np.testing.assert_allclose(cells, df[name].to_numpy(), rtol=0, atol=1e-9, err_msg=f"column {col} ({name})")
