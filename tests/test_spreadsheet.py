"""fusionlab.spreadsheet: the terminal-log parser, and the Lab 03 spreadsheet (data/lab03_fusion.xlsx): reproducible,
and its live formulas equal the Python pipeline."""

import hashlib
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from fusionlab import correlation as co, spreadsheet

DATA = Path(__file__).resolve().parents[1] / "data"
XLSX = DATA / "lab03_fusion.xlsx"


def _sha(path):
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def test_spreadsheet_regenerates_byte_identical(tmp_path):
    counts = spreadsheet.parse_terminal_log(DATA / "lab03" / "motion.log")
    out = spreadsheet.write_spreadsheet(counts, tmp_path / "x.xlsx", 0.02)
    assert _sha(out) == _sha(XLSX)
    assert _sha(XLSX) in (DATA / "README.md").read_text()


def test_spreadsheet_holds_formulas_for_every_step():
    openpyxl = pytest.importorskip("openpyxl")
    ws = openpyxl.load_workbook(XLSX)["fusion"]
    assert ws["F3"].value == "=ATAN2(E3,D3)"  # Excel order: the tilt (000 eq 5.5)
    assert ws["P3"].value == "=O3*H3+(1-O3)*(P2+L3)"  # (000 eq 5.17)
    assert [ws.cell(1, k).value[:2] for k in range(4, 18)] == [
        "a)",
        "a)",
        "b)",
        "c)",
        "d)",
        "e)",
        "f)",
        "g)",
        "h)",
        "e'",
        "i)",
        "j)",
        "k)",
        "l)",
    ]


def test_libreoffice_recalculation_equals_pipeline(tmp_path):
    soffice = shutil.which("soffice") or shutil.which("libreoffice")
    if soffice is None:
        pytest.skip(
            "LibreOffice not found: install it (Debian: apt-get install libreoffice-calc-nogui) "
            "to recalculate data/lab03_fusion.xlsx headless"
        )
    openpyxl = pytest.importorskip("openpyxl")
    subprocess.run(
        [
            soffice,
            "--headless",
            "--norestore",
            f"-env:UserInstallation=file://{tmp_path}/profile",
            "--convert-to",
            "xlsx",
            "--outdir",
            str(tmp_path / "out"),
            str(XLSX),
        ],
        check=True,
        capture_output=True,
        timeout=180,
    )
    ws = openpyxl.load_workbook(tmp_path / "out" / XLSX.name, data_only=True)["fusion"]
    df = co.pipeline(spreadsheet.parse_terminal_log(DATA / "lab03" / "motion.log"), 0.02)
    rows = range(2, len(df) + 2)
    for col, name in spreadsheet.SHEET_TO_PIPELINE.items():
        cells = np.array([ws[f"{col}{r}"].value for r in rows], dtype=float)
        np.testing.assert_allclose(cells, df[name].to_numpy(), rtol=0, atol=1e-9, err_msg=f"column {col} ({name})")


# --- the terminal log ---------------------------------------------------------------------------------------------

LAB03 = DATA / "lab03"
GOOD = "menu\r\nAX AY AZ GX GY\r\n1FF 200 266 1C3 1C4\r\n200 201 265 1C4 1C3\r\n0\r\nStopped.\r\n"


# --- parser -------------------------------------------------------------------------------------------------------


def test_parser_reads_hex_counts():
    c = spreadsheet.parse_terminal_log(GOOD)
    np.testing.assert_array_equal(c, [[0x1FF, 0x200, 0x266, 0x1C3, 0x1C4], [0x200, 0x201, 0x265, 0x1C4, 0x1C3]])


@pytest.mark.parametrize(
    "bad, line, what",
    [
        ("1FF 200 2G6 1C3 1C4", 4, "hexadecimal"),  # bad hex
        ("1FF 200 266 1C3", 4, "expected 5"),  # short line
        ("1FF 200 2\x00\x7f\x03 1C3 1C4", 4, "binary"),  # binary junk
        ("1FF 200 466 1C3 1C4", 4, "10-bit"),  # beyond the ADC
    ],
)
def test_corrupted_line_is_reported_with_its_line_number(bad, line, what):
    text = GOOD.replace("200 201 265 1C4 1C3", bad)
    with pytest.raises(spreadsheet.LogParseError, match=rf"line {line}: .*{what}"):
        spreadsheet.parse_terminal_log(text)


def test_truncated_last_line_is_reported_not_dropped():
    text = "AX AY AZ GX GY\n1FF 200 266 1C3 1C4\n1FF 20"
    with pytest.raises(spreadsheet.LogParseError, match="line 3"):
        spreadsheet.parse_terminal_log(text)


def test_not_a_terminal_log_is_a_clear_error():
    with pytest.raises(spreadsheet.LogParseError, match="not a NanoCore12 terminal log"):
        spreadsheet.parse_terminal_log("sample,t_s,angle_x_deg\n0,0.0,0.0\n")


def test_two_sections_need_the_plural_parser():
    with pytest.raises(spreadsheet.LogParseError, match="2 data sections"):
        spreadsheet.parse_terminal_log(GOOD + GOOD)
    assert [len(s) for s in spreadsheet.parse_terminal_sessions(GOOD + GOOD)] == [2, 2]


def test_missing_file_is_not_mistaken_for_log_text():
    with pytest.raises(FileNotFoundError, match="no such file"):
        spreadsheet.parse_terminal_log("data/lab03/no_such.log")


# --- the parser accepts exactly what the MCU writes, and drops nothing silently --------------------------------------

MOTION = (LAB03 / "motion.log").read_bytes().decode("latin-1")
LINES = MOTION.split("\r\n")
FIRST = LINES.index("AX AY AZ GX GY") + 1  # index of the first data line


def _with(line_index, text):
    lines = list(LINES)
    lines[line_index] = text
    return "\r\n".join(lines)


@pytest.mark.parametrize(
    "bad, what",
    [
        ("0", r"a lone '0' inside the data, not followed by 'Stopped\.'"),
        ("Stopped", r"expected 5 hex values .* got 1: 'Stopped'"),
        ("0x25D 1D8 25D 1D2 1C9", r"'0x25D': the MCU prints each count as exactly 3 hex digits"),
        ("+25D 1D8 25D 1D2 1C9", r"'\+25D'"),
        ("2_5D 1D8 25D 1D2 1C9", r"'2_5D'"),
        ("-1 1D8 25D 1D2 1C9", r"'-1'"),
        ("25D 1D8 25D 1D2 1C9\f", r"control characters \\x0c"),
    ],
)
def test_a_line_truncated_or_not_in_the_mcu_format_is_reported_not_dropped(bad, what):
    with pytest.raises(spreadsheet.LogParseError, match=rf"^line {FIRST + 101}: .*{what}"):
        spreadsheet.parse_terminal_log(_with(FIRST + 100, bad))


def test_the_stop_sequence_and_the_mcu_variants_parse_in_full():
    n = len(spreadsheet.parse_terminal_log(MOTION))
    assert n == 550
    assert len(spreadsheet.parse_terminal_log(MOTION.replace(" ", "\t"))) == n  # tab-separated
    assert len(spreadsheet.parse_terminal_log(b"\xef\xbb\xbf" + MOTION.encode())) == n  # UTF-8 BOM
    assert len(spreadsheet.parse_terminal_log("\ufeff" + MOTION)) == n
    assert len(spreadsheet.parse_terminal_log(MOTION.replace("\r\n", "\n"))) == n  # LF line ends


def test_a_form_feed_in_the_menu_does_not_shift_line_numbers():
    text = _with(2, LINES[2] + "\f")  # inside the menu text: ignored
    text = text.split("\r\n")
    text[FIRST + 200] = "1FF 2G0 266 1C3 1C4"
    with pytest.raises(spreadsheet.LogParseError, match=rf"^line {FIRST + 201}: not a hexadecimal ADC value"):
        spreadsheet.parse_terminal_log("\r\n".join(text))


def test_every_unusable_line_is_counted_and_the_first_few_are_shown():
    lines = list(LINES)
    for k in (10, 20, 30, 40, 50, 60, 70):
        lines[FIRST + k] = "1FF 200"
    with pytest.raises(
        spreadsheet.LogParseError,
        match=rf"^7 lines of the log cannot be used: line {FIRST + 11}: expected 5 "
        r".*\.\.\. and 2 more$",
    ):
        spreadsheet.parse_terminal_log("\r\n".join(lines))


def test_data_after_the_stop_without_a_header_is_reported():
    text = MOTION + "\r\n1FF 200 266 1C3 1C4\r\n"  # the log ends at the menu prompt
    last = len(MOTION.split("\r\n")) + 1
    with pytest.raises(spreadsheet.LogParseError, match=rf"line {last}: data line outside a recording"):
        spreadsheet.parse_terminal_log(text)


def test_the_parser_reads_as_many_hex_digits_as_the_adc_has_bits_and_refuses_an_impossible_adc():
    text = "AX AY AZ GX GY\n800 801 A6C 7FF 800\n"  # a 12-bit ADC prints 3 hex digits
    assert spreadsheet.parse_terminal_sessions(text, bits=12)[0].tolist() == [[2048, 2049, 2668, 2047, 2048]]
    with pytest.raises(spreadsheet.LogParseError):
        spreadsheet.parse_terminal_sessions(text, bits=10)  # 10 bits: 3 digits, but 0xA6C > 1023
    for bits in (0, 33, 10.5, "10", True):
        with pytest.raises(ValueError, match=r"bits must be a whole number of ADC bits between 1 and 32"):
            spreadsheet.parse_terminal_sessions(text, bits=bits)
