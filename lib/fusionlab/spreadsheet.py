"""The seed-000 lab's data files: the terminal log and the live spreadsheet (seed 000 §5.4, Lab 3 Parts 2-3).

The thesis' Lab 3 logs the NanoCore12's raw ADC counts through a terminal program (space-delimited hex values
between menu text, §5.4 Part 2) and fuses them in Excel, one column per step a)-l) (§5.4 Part 3, "Data Analysis in
Excel"). This module reads such a log (:func:`parse_terminal_log`, every section with
:func:`parse_terminal_sessions`; a malformed line raises :class:`LogParseError` naming its line number) and writes
the spreadsheet with **live formulas** (:func:`write_spreadsheet`), whose every column equals the matching column of
:func:`fusionlab.correlation.pipeline` (the step functions and the fusion itself are
:mod:`fusionlab.correlation`).

Command line: ``python -m fusionlab.spreadsheet --log data/lab03/motion.log --xlsx data/lab03_fusion.xlsx``.

Units: ADC counts in the log (10-bit by default, :data:`fusionlab.sensors.ADC_BITS`); the spreadsheet works in g,
degrees and °/s like the thesis (eq 5.6 converts to degrees before any other step), for the X axis.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from . import sensors, validate

__all__ = [
    "LogParseError",
    "parse_terminal_sessions",
    "parse_terminal_log",
    "write_spreadsheet",
    "HEADER",
    "SHEET_COLUMNS",
    "SHEET_TO_PIPELINE",
    "main",
]


#: The column header line the MCU prints at the start of each data section.
HEADER = ("AX", "AY", "AZ", "GX", "GY")


# ----------------------------------------------------------------------------------------------------------------
# The terminal log (seed 000 §5.4 Part 2-3: space-delimited hex ADC values between menu text)
# ----------------------------------------------------------------------------------------------------------------


class LogParseError(ValueError):
    """A terminal log that cannot be read; the message names the line number and shows the line."""


def _read_text(log):
    if isinstance(log, str) and log.strip() and "\n" not in log.strip() and Path(log.strip()).exists():
        log = Path(log.strip())  # a path copied with its line end ("motion.log\n")
    if isinstance(log, (bytes, bytearray)):
        raw = bytes(log)
    elif isinstance(log, Path) or (isinstance(log, str) and "\n" not in log and Path(log).is_file()):
        if Path(log).is_dir():
            raise ValueError(f"log must be a terminal log file; got the directory {str(log)!r} (name a file in it)")
        raw = Path(log).read_bytes()
    elif isinstance(log, str):
        if "\n" not in log and tuple(log.split()) != HEADER:
            raise FileNotFoundError(f"log: no such file {log!r} (pass a path to a terminal log, or its text)")
        return log.removeprefix("\ufeff")
    else:
        raise ValueError(f"log must be a path, str or bytes; got {type(log).__name__}")
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        return raw.decode("utf-16").removeprefix("\ufeff")  # a log saved as UTF-16 by an editor
    if raw[:200].count(b"\x00") > len(raw[:200]) // 4:
        raise ValueError(
            "log must be text in one byte per character (ASCII, Latin-1 or UTF-8); got bytes with "
            "NUL characters between the letters, as UTF-16 without a byte-order mark -- save it as "
            "UTF-8"
        )
    return raw.removeprefix(b"\xef\xbb\xbf").decode("latin-1")  # a UTF-8 byte-order mark is not text


#: Line ends of a terminal capture: CR LF (Tera Term), LF or CR. Nothing else splits a line (str.splitlines would
#: also split at a form feed or a vertical tab and shift every later line number).
_LINE_END = re.compile(r"\r\n|\r|\n")
_MAX_REPORTED = 5


def parse_terminal_sessions(log: str | Path | bytes, bits: int = sensors.ADC_BITS) -> list[np.ndarray]:
    r"""Every "Get RAW Sensor Data" section of a terminal log, as ADC counts.

    The format is exactly what the MCU prints (:func:`fusionlab.simulate.terminal_log`): a section starts at the
    column header line ``AX AY AZ GX GY``; every data line holds five counts, each written as exactly
    ``ceil(bits / 4)`` hex digits (``25D`` for 10 bits; no ``0x``, sign or ``_``), separated by spaces (tabs are
    accepted too); the section ends at the stop key the MCU echoes, a line ``0`` followed by ``Stopped.``, or at
    the end of the file. Blank lines are allowed. Text outside the sections (the menu) is skipped.

    Nothing is dropped silently: every line that cannot be used -- bad hex, a short, merged or truncated line
    (including one truncated to ``0`` or ``Stopped``), control characters, a value beyond the ADC, or a data line
    outside any section -- is reported by one :class:`LogParseError` that gives the count and the first few lines
    with their line numbers (counted at CR LF, LF or CR line ends only).

    Parameters
    ----------
    log : str, pathlib.Path or bytes
        A path to the log, or its text (str), or its bytes (UTF-8; a byte-order mark is ignored).
    bits : int, optional
        ADC resolution in bits (10 on the NanoCore12).

    Returns
    -------
    list of ndarray
        One int64 array of shape (N_i, 5) per section: AX AY AZ GX GY counts.

    Raises
    ------
    LogParseError
        If a line is unusable (see above), or if the text holds no ``AX AY AZ GX GY`` header (not a terminal log).

    Examples
    --------
    >>> text = "menu\nAX AY AZ GX GY\n200 201 26C 1FF 200\n201 200 26B 200 1FE\n0\nStopped.\n"
    >>> parse_terminal_sessions(text)
    [array([[512, 513, 620, 511, 512],
           [513, 512, 619, 512, 510]])]
    """
    text = _read_text(log)
    top = sensors.adc_full_scale(bits)  # checks bits (1-32) with the ADC functions' message
    bits = top.bit_length()
    digits = -(-bits // 4)
    token = re.compile(rf"[0-9A-Fa-f]{{{digits}}}")
    lines = _LINE_END.split(text)
    sections, rows, inside, problems = [], None, False, []
    i = 0
    while i < len(lines):
        lineno, line = i + 1, lines[i]
        i += 1
        s = line.strip(" \t")
        if tuple(s.split()) == HEADER:
            if inside:
                sections.append(rows)
            rows, inside = [], True
            continue
        if not inside:
            tokens = s.split()
            if len(tokens) >= 3 and all(token.fullmatch(t) for t in tokens):
                problems.append(
                    f"line {lineno}: data line outside a recording (no 'AX AY AZ GX GY' header "
                    f"before it since the last stop): {line[:60]!r}"
                )
            continue
        if not s:
            continue
        if s == "0":  # the stop key, echoed; the MCU then prints "Stopped."
            j = i
            while j < len(lines) and not lines[j].strip():
                j += 1
            if j == len(lines) or lines[j].strip() == "Stopped.":
                sections.append(rows)
                inside = False
                i = j + 1
                continue
            problems.append(
                f"line {lineno}: a lone '0' inside the data, not followed by 'Stopped.' (a truncated "
                "data line? the MCU ends a recording with '0' then 'Stopped.')"
            )
            continue
        if any(not (32 <= ord(ch) < 127 or ch == "\t") for ch in s):
            bad = sorted({ch for ch in s if not (32 <= ord(ch) < 127 or ch == "\t")})
            kind = (
                "non-text (binary) characters"
                if any(ord(ch) >= 127 or ch == "\x00" for ch in bad)
                else "control characters " + "".join(repr(ch)[1:-1] for ch in bad)
            )
            problems.append(f"line {lineno}: {kind} in a data line: {line[:40]!r}")
            continue
        tokens = s.split()
        if len(tokens) != 5:
            problems.append(
                f"line {lineno}: expected 5 hex values (AX AY AZ GX GY), got {len(tokens)}: "
                f"{line[:60]!r} (truncated or merged line?)"
            )
            continue
        try:
            vals = [int(tok, 16) for tok in tokens]
        except ValueError:
            problems.append(f"line {lineno}: not a hexadecimal ADC value in {line[:60]!r}")
            continue
        odd = [tok for tok in tokens if not token.fullmatch(tok)]
        if odd:
            problems.append(
                f"line {lineno}: not a hexadecimal ADC value in {line[:60]!r} ({odd[0]!r}: the MCU "
                f"prints each count as exactly {digits} hex digits)"
            )
            continue
        if any(v > top for v in vals):
            problems.append(f"line {lineno}: value above the {bits}-bit ADC range 0..{top:X}: {line[:60]!r}")
            continue
        rows.append(vals)
    if inside:
        sections.append(rows)
    if problems:
        if len(problems) == 1:
            raise LogParseError(problems[0])
        more = f"; ... and {len(problems) - _MAX_REPORTED} more" if len(problems) > _MAX_REPORTED else ""
        raise LogParseError(
            f"{len(problems)} lines of the log cannot be used: " + "; ".join(problems[:_MAX_REPORTED]) + more
        )
    if not sections:
        raise LogParseError("not a NanoCore12 terminal log: no 'AX AY AZ GX GY' header line was found")
    return [np.array(r, dtype=np.int64).reshape(-1, 5) for r in sections]


def parse_terminal_log(log: str | Path | bytes, bits: int = sensors.ADC_BITS) -> np.ndarray:
    """The one "Get RAW Sensor Data" section of a terminal log, as an (N, 5) int64 array of counts.

    See :func:`parse_terminal_sessions` for the format and the errors; this one also raises if the log holds more
    than one section (clear the screen between recordings, as the lab says, or use the plural function).

    Parameters
    ----------
    log : str, pathlib.Path or bytes
        A path to the log, or its text, or its bytes.
    bits : int, optional
        ADC resolution in bits.

    Returns
    -------
    ndarray of int64, shape (N, 5)
        AX AY AZ GX GY counts.

    Raises
    ------
    LogParseError
        As :func:`parse_terminal_sessions`, and if the log holds more than one section.
    """
    sections = parse_terminal_sessions(log, bits)
    if len(sections) != 1:
        raise LogParseError(f"log holds {len(sections)} data sections; expected 1 (use parse_terminal_sessions)")
    if len(sections[0]) == 0:
        raise LogParseError("log holds a data header but no data lines")
    return sections[0]


# ----------------------------------------------------------------------------------------------------------------
# The live spreadsheet (seed 000 §5.4 Part 3: "Data Analysis in Excel")
# ----------------------------------------------------------------------------------------------------------------

#: Column letter and header of each step in the ``fusion`` sheet of :func:`write_spreadsheet`.
SHEET_COLUMNS = {
    "A": "AY counts",
    "B": "AZ counts",
    "C": "GX counts",
    "D": "a) Ay (g)",
    "E": "a) Az (g)",
    "F": "b) ATAN2 (rad)",
    "G": "c) angle (deg)",
    "H": "d) angle MA (deg)",
    "I": "e) dA/dt (deg/s)",
    "J": "f) GX (deg/s)",
    "K": "g) gyro cumulative (deg)",
    "L": "h) gyro increment (deg)",
    "M": "e') dA/dt MA (deg/s)",
    "N": "i) ratio",
    "O": "j) accel weight",
    "P": "k) fused (deg)",
    "Q": "l) fused MA (deg)",
}
#: The pipeline column each spreadsheet column must equal (``None``: a raw count, or the smoothed derivative).
SHEET_TO_PIPELINE = {
    "D": "a_acc_y_g",
    "E": "a_acc_z_g",
    "F": "b_angle_rad",
    "G": "c_angle_deg",
    "H": "d_angle_ma_deg",
    "I": "e_dangle_dps",
    "J": "f_gyro_dps",
    "K": "g_gyro_cum_deg",
    "L": "h_gyro_inc_deg",
    "N": "i_ratio",
    "O": "j_accel_weight",
    "P": "k_fused_deg",
    "Q": "l_fused_ma_deg",
}


def write_spreadsheet(
    counts: ArrayLike, path: str | Path, dt: float, n_ma: int = 12, accel_weight: str = "ratio", eps: float = 1e-9
) -> Path:
    """Write the Lab 3 spreadsheet: the raw log, parameters, and steps a)-l) as **live formulas** (seed 000 §5.4.3).

    Sheets: ``log`` (the hex text split into columns AX..GY, as *Text to Columns* leaves it), ``params`` (dt,
    Vref, ADC full scale, zero levels, sensitivities, N, ε -- change one and every formula follows) and ``fusion``
    (one column per step, :data:`SHEET_COLUMNS`) for the X axis, "as meant" (Excel ``ATAN2(z, y)`` = the tilt,
    rectangular increments, averaged derivative in the ratio). The formulas use only functions Excel and
    LibreOffice share (HEX2DEC, ATAN2, DEGREES, AVERAGE, OFFSET, MIN, ABS, ROW). After recalculation every column
    equals the matching column of :func:`fusionlab.correlation.pipeline` (``variant='meant'``), see
    :data:`SHEET_TO_PIPELINE`.
    The file is byte-identical for the same inputs (fixed timestamps inside the zip).

    Parameters
    ----------
    counts : array_like of int, shape (N, 5)
        AX AY AZ GX GY counts.
    path : str or pathlib.Path
        The .xlsx file to write.
    dt : float
        Sample interval, s.
    n_ma : int, optional
        Window of the moving averages, samples.
    accel_weight : {'ratio', 'one_minus_ratio'}, optional
        As :func:`fusionlab.correlation.pipeline`.
    eps : float, optional
        The ε of the ratio.

    Returns
    -------
    pathlib.Path
        The file written.
    """
    import io
    import zipfile
    import re
    from openpyxl import Workbook

    c = validate.samples(counts, "counts", 5).astype(np.int64)
    dt = validate.time_step(dt, "dt")
    if accel_weight not in ("ratio", "one_minus_ratio"):
        raise ValueError(f"accel_weight must be 'ratio' or 'one_minus_ratio'; got {accel_weight!r}")
    wb = Workbook()
    log = wb.active
    log.title = "log"
    log.append(list(HEADER))
    for row in c:
        log.append([f"{v:03X}" for v in row])
    par = wb.create_sheet("params")
    acc, gyr = sensors.ADXL335, sensors.IDG500
    for name, value in [
        ("dt (s)", dt),
        ("Vref (V)", 3.0),
        ("ADC full scale (2^bits - 1)", 1023),
        ("accel zero-g level (V)", acc.zero_level),
        ("accel sensitivity (V/g)", acc.sensitivity),
        ("gyro zero-rate level (V)", gyr.zero_level),
        ("gyro sensitivity (V/(deg/s))", gyr.sensitivity),
        ("N moving average", int(n_ma)),
        ("epsilon", eps),
    ]:
        par.append([name, value])
    P = {k: f"params!$B${i}" for i, k in enumerate(["dt", "vref", "fs", "az", "as", "gz", "gs", "n", "eps"], 1)}
    ws = wb.create_sheet("fusion")
    ws.append(list(SHEET_COLUMNS.values()))

    def ma(col, r):
        k = f"MIN({P['n']},ROW()-1)"
        return f"=AVERAGE(OFFSET({col}{r},1-{k},0,{k},1))"

    for i in range(len(c)):
        r = i + 2
        f = {
            "A": f"=HEX2DEC(log!B{r})",
            "B": f"=HEX2DEC(log!C{r})",
            "C": f"=HEX2DEC(log!D{r})",
            "D": f"=(A{r}*{P['vref']}/{P['fs']}-{P['az']})/{P['as']}",  # a) (000 eq 5.2)
            "E": f"=(B{r}*{P['vref']}/{P['fs']}-{P['az']})/{P['as']}",  # a) (000 eq 5.3)
            "F": f"=ATAN2(E{r},D{r})",  # b) (000 eq 5.5, Excel order)
            "G": f"=DEGREES(F{r})",  # c) (000 eq 5.6)
            "H": ma("G", r),  # d) (000 eq 5.7)
            "I": "=0" if i == 0 else f"=(H{r}-H{r - 1})/{P['dt']}",  # e) (000 eq 5.9)
            "J": f"=(C{r}*{P['vref']}/{P['fs']}-{P['gz']})/{P['gs']}",  # f) (000 eq 5.11)
            "K": f"=J{r}*{P['dt']}" if i == 0 else f"=K{r - 1}+J{r}*{P['dt']}",  # g)
            "L": f"=J{r}*{P['dt']}",  # h) (000 eq 5.13, corrected)
            "M": ma("I", r),
            "N": f"=ABS(J{r})/(ABS(J{r})+ABS(M{r})+{P['eps']})",  # i) (000 eq 5.15)
            "O": f"=N{r}" if accel_weight == "ratio" else f"=1-N{r}",  # j)
            "P": (
                f"=O{r}*H{r}+(1-O{r})*(H{r}+L{r})"
                if i == 0  # k) (000 eq 5.17), F[-1] = H2
                else f"=O{r}*H{r}+(1-O{r})*(P{r - 1}+L{r})"
            ),
            "Q": ma("P", r),  # l) (000 eq 5.19)
        }
        for col, formula in f.items():
            ws[f"{col}{r}"] = formula
    buf = io.BytesIO()
    wb.save(buf)
    out = io.BytesIO()
    with zipfile.ZipFile(io.BytesIO(buf.getvalue())) as zin, zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as zout:
        for item in sorted(zin.infolist(), key=lambda z: z.filename):
            data = zin.read(item.filename)
            if item.filename == "docProps/core.xml":
                data = re.sub(rb"(<dcterms:(created|modified)[^>]*>)[^<]*", rb"\g<1>2000-01-01T00:00:00Z", data)
            zout.writestr(
                zipfile.ZipInfo(item.filename, date_time=(2000, 1, 1, 0, 0, 0)),
                data,
                compress_type=zipfile.ZIP_DEFLATED,
            )
    Path(path).write_bytes(out.getvalue())
    return Path(path)


def main(argv: list[str] | None = None) -> None:
    """``python -m fusionlab.spreadsheet --xlsx data/lab03_fusion.xlsx``: the Lab 3 spreadsheet of the motion log.

    Parameters
    ----------
    argv : list of str, optional
        Command-line arguments (default: ``sys.argv[1:]``): ``--log`` the terminal log, ``--xlsx`` the spreadsheet
        to write, ``--dt`` the sample interval in s.
    """
    import argparse

    parser = argparse.ArgumentParser(
        prog="python -m fusionlab.spreadsheet",
        description="Write the Lab 03 spreadsheet (raw log + live formulas a)-l)).",
    )
    parser.add_argument("--log", default="data/lab03/motion.log")
    parser.add_argument("--xlsx", default="data/lab03_fusion.xlsx")
    parser.add_argument("--dt", type=float, default=0.02)
    args = parser.parse_args(argv)
    print(f"wrote {write_spreadsheet(parse_terminal_log(args.log), args.xlsx, args.dt)}")


if __name__ == "__main__":
    main()
