"""What a lab's prose claims and what backs it: the machinery of tests/test_claims.py (its docstring states the rule).

A number of the prose is tied to its *quantity*: a printed number backs it only in the prose's section (or the part,
exercise or question its sentence names), with the prose's unit, and -- read from a table -- on the row or column its
clause names; a count ("9 trials") only beside its noun. A literal set in code backs it as a parameter of the
notebook, never a figure's size or style. A number quoted from a seed is backed by the seed's value listed with its
place in tests/seed_numbers.csv (the seeds themselves are not part of the course); one quoted from the benchmark by
the README's table and lib/fusionlab/data/capstone_bar.csv.
"""

from __future__ import annotations

import ast
import csv
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

from notebook_text import ROOT, is_header, load, outputs, read_text, source

SEED_TABLE = Path(__file__).with_name("seed_numbers.csv")

NUMBER = re.compile(
    r"(?<![\w.^_\\/{-])(?P<sign>[−-])?"
    r"(?P<num>\d{1,3}(?:,\d{3})+|\d{1,3}(?:[ \u202f\u00a0]\d{3})+(?![\d.])|\d+)"
    r"(?P<frac>\.\d+)?"
    r"(?:[eE](?P<exp>[−+-]?\d+)|\s?[·×]\s?10(?P<sup>[⁻⁺]?[⁰¹²³⁴⁵⁶⁷⁸⁹]+))?(?![\w]|\.\d)"
)
RANGE_DASH = re.compile(r"(?<=\d)\s*[–]\s*(?=\d)")
RATIO = re.compile(r"\s?(?:×|times\b)(?!\s*\d)")
_SUP = str.maketrans("⁻⁺⁰¹²³⁴⁵⁶⁷⁸⁹", "-+0123456789")

# units, longest first; a unit is what follows a number (after at most one space)
_UNITS = [
    "°/h/√Hz",
    "µrad/s/√Hz",
    "µ°/s/√Hz",
    "°/√h",
    "°/h",
    "°/s",
    "rad/s²",
    "rad/s",
    "m/s²",
    "m/s",
    "µrad",
    "mrad",
    "rad",
    "µg/√Hz",
    "µg",
    "mg",
    "dB",
    "ms",
    "µs",
    "kHz",
    "Hz",
    "km",
    "cm",
    "mm",
    "µT",
    "nT",
    "rpm",
    "deg/s",
    "deg",
    "°",
    "%",
    "s",
    "m",
    "g",
]
UNIT = re.compile(r"\s?(?P<u>" + "|".join(re.escape(u) for u in _UNITS) + r")(?![\w²/])")
_ALIAS = {"deg": "°", "deg/s": "°/s"}


def _unit(text, end):
    """The unit written right after a number that ends at ``end`` (None if none)."""
    m = UNIT.match(text, end)
    return _ALIAS.get(m.group("u"), m.group("u")) if m else None


def _line_units(line):
    """The units a printed line names in words for its bare numbers: "(deg)", "[m]", "(RMSE, deg)"."""
    found = set()
    for m in re.finditer(r"[(\[,]\s*(?P<u>[^()\[\],\s]+)\s*[)\]]", line):
        u = _ALIAS.get(m.group("u"), m.group("u"))
        if u in _UNITS:
            found.add(u)
    return found


def _printed_unit(line, end):
    """The unit after a printed number, or after the bracket that closes its list: "[0.0658 0.0091] rad"."""
    u = _unit(line, end)
    if u is None:
        m = re.match(r"[\s\d.eE+−-]*\]", line[end:])
        if m:
            u = _unit(line, end + m.end())
    return u


STOP = set(
    """the a an and or of to in on at by for from with as is are be was were it its this that these those
which what when where who how than then there their they them we our ours you your his her not no nor but if so such
into onto over under about after before between each every all any both more most less least only also same other
one two three four five six seven eight nine ten per via vs gives give given gets get has have had does did do
can could would should may might must will shall here now just very much many few while whose out up down off
deg rad ms hz""".split()
)


def words(text):
    """The content words of a text, lower case, a plural's 's' dropped: 'held-out trials' -> {'held', 'trial'}."""
    out = set()
    for w in re.findall(r"[A-Za-zÀ-ÿα-ωΑ-Ω]+", text.replace("_", " ")):
        w = w.lower()
        if len(w) < 3 or w in STOP:
            continue
        if len(w) > 4 and w.endswith("s") and not w.endswith("ss"):
            w = w[:-1]
        out.add(w)
    return out


def value(m):
    """(value, significant digits) of a NUMBER match."""
    digits = re.sub(r"[, \u202f\u00a0]", "", m.group("num")) + (m.group("frac") or "")
    exp = m.group("exp") or (m.group("sup").translate(_SUP) if m.group("sup") else None)
    s = digits + (f"e{exp.replace('−', '-')}" if exp else "")
    return float(s), significant(digits)


def significant(digits):
    d = digits.lstrip("0").replace(".", "")
    if "." in digits:
        return max(1, len(d.lstrip("0")) if digits.startswith("0") or digits.startswith(".") else len(d))
    return max(1, len(d.rstrip("0")) or 1)


# ----------------------------------------------------------------------------------------------------------------
# sections

HEADING = re.compile(r"^##\s+(?P<title>.+)$", re.M)
SUBHEADING = re.compile(r"^###\s+(?P<title>(?:Exercise|Q)\s*\d+)\b", re.M)
SUMMARY = re.compile(r"^(?:Summary|Conclusions?|What you found|Take-aways)\b", re.I)


def sections(nb):
    """Per cell, (offset, section) pairs: a ``## `` heading starts a section (the cells before the first are section
    0; prose before a heading in the same cell belongs to the section above); and {name: section} for the parts,
    exercises and questions the notebook names ('part c', 'exercise 3', 'q2'), and {section: title}."""
    sec, names, current, titles = [], {}, 0, {0: ""}
    for cell in load(nb)["cells"]:
        text = source(cell) if cell["cell_type"] == "markdown" else ""
        marks = [(0, current)]
        for m in HEADING.finditer(text):
            current = max(titles) + 1
            titles[current] = m.group("title")
            marks.append((m.start(), current))
            part = re.match(r"Part\s+([A-Z])\b", m.group("title"))
            if part:
                names[f"part {part.group(1).lower()}"] = current
        sec.append(marks)
        for m in SUBHEADING.finditer(text):
            names[re.sub(r"\s+", "", m.group("title").lower()).replace("exercise", "exercise ")] = current
    return sec, names, titles


def section_at(marks, offset):
    return [s for o, s in marks if o <= offset][-1]


REFERS = re.compile(
    r"\b(?:Parts?\s+(?P<parts>[A-Z](?:\s*(?:,|and|–|-)\s*[A-Z])*)\b|(?P<ex>Exercises?|Q)\s*"
    r"(?P<n>\d+(?:\s*(?:,|and|–)\s*\d+)*))"
)


def referred_sections(sentence, names):
    """The sections a sentence names: 'Part C', 'Parts B and D', 'Exercise 3', 'Q2'."""
    out = set()
    for m in REFERS.finditer(sentence):
        if m.group("parts"):
            for p in re.findall(r"[A-Z]", m.group("parts")):
                if f"part {p.lower()}" in names:
                    out.add(names[f"part {p.lower()}"])
        else:
            kind = "q" if m.group("ex") == "Q" else "exercise "
            for n in re.findall(r"\d+", m.group("n")):
                if f"{kind}{n}" in names:
                    out.add(names[f"{kind}{n}"])
    return out


# ----------------------------------------------------------------------------------------------------------------
# what the code cells print and set


@dataclass
class Printed:
    value: float
    sig: int | None  # None: a literal set in code
    ratio: bool
    unit: str | None
    units: frozenset  # the units the line names in words
    context: frozenset  # the words of its line (and of its table's header, for a row with no words of its own)
    section: int
    text: str = ""
    other: frozenset = frozenset()  # the words of a table's other columns
    column: frozenset | None = None  # in a table: the words of its column's header
    table: int | None = None
    row: frozenset = frozenset()  # the words of its own line
    beside: frozenset = frozenset()  # the words right before and after it on its line


PLOT_CALLS = {
    "figure",
    "subplots",
    "plot",
    "loglog",
    "semilogx",
    "semilogy",
    "scatter",
    "bar",
    "barh",
    "hist",
    "axhline",
    "axvline",
    "axhspan",
    "axvspan",
    "fill_between",
    "text",
    "annotate",
    "legend",
    "set_xlim",
    "set_ylim",
    "xlim",
    "ylim",
    "set_xticks",
    "set_yticks",
    "grid",
    "tight_layout",
    "subplots_adjust",
    "add_subplot",
    "colorbar",
    "imshow",
    "pcolormesh",
    "contour",
    "step",
    "errorbar",
    "set_title",
    "suptitle",
    "savefig",
    "set_aspect",
    "twinx",
    "inset_axes",
    "stem",
    "boxplot",
    "violinplot",
    "quiver",
    "arrow",
    "Rectangle",
    "Circle",
    "FancyArrowPatch",
    "set_position",
    "margins",
    "tick_params",
    "set_size_inches",
}
PLOT_KEYWORDS = {
    "figsize",
    "dpi",
    "alpha",
    "lw",
    "linewidth",
    "ms",
    "markersize",
    "fontsize",
    "size",
    "width",
    "height",
    "s",
    "zorder",
    "pad",
    "wspace",
    "hspace",
    "rotation",
    "ncol",
    "bins",
    "loc",
    "labelsize",
    "length",
    "headwidth",
    "headlength",
    "ls",
    "capsize",
    "elinewidth",
    "framealpha",
    "shrink",
    "aspect",
    "bottom",
    "top",
    "left",
    "right",
    "color",
    "c",
}


def _call_name(node):
    f = node.func
    return f.attr if isinstance(f, ast.Attribute) else f.id if isinstance(f, ast.Name) else ""


def set_in_code(code, named=False):
    """The numbers a cell sets: literals assigned to a name, passed to a function, given as a default or written in a
    literal list (``d = 0.1``, ``runs=60``, ``[1e-8] * 3``), not a literal inside arithmetic such as ``0.06**2``, and
    nothing of a figure's drawing (``figsize=(7, 3.4)``, ``alpha=0.3``, ``ax.axhline(0.5)``). With ``named``, each
    with the words of what it is set to (``runs=60`` -> {'run'})."""
    code = "\n".join(line for line in code.splitlines() if not line.lstrip().startswith(("%", "!")))
    try:
        tree = ast.parse(code)
    except SyntaxError:
        return []
    skip = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and _call_name(node) in PLOT_CALLS:
            skip.update(id(n) for n in ast.walk(node))
        elif isinstance(node, ast.keyword) and node.arg in PLOT_KEYWORDS:
            skip.update(id(n) for n in ast.walk(node))
    found = []
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        kids, name = [], ""
        if isinstance(node, (ast.Assign, ast.AnnAssign)):
            kids = [node.value]
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            name = " ".join(n.id for t in targets for n in ast.walk(t) if isinstance(n, ast.Name))
        elif isinstance(node, ast.keyword):
            kids, name = [node.value], node.arg or ""
        elif isinstance(node, ast.Call):
            kids, name = list(node.args), _call_name(node)
        elif isinstance(node, (ast.List, ast.Tuple)):
            kids = list(node.elts)
        elif isinstance(node, ast.arguments):
            kids = [d for d in node.defaults + node.kw_defaults if d is not None]
        while kids:
            k = kids.pop()
            if isinstance(k, (ast.Tuple, ast.List, ast.Set)):
                kids += k.elts
            elif isinstance(k, ast.UnaryOp):
                kids.append(k.operand)
            elif isinstance(k, ast.Constant) and type(k.value) in (int, float) and id(k) not in skip:
                found.append((abs(float(k.value)), frozenset(words(name))) if named else abs(float(k.value)))
    return found


def _segments(line):
    """(start, end, words) of the parts of a line separated by two spaces or more (a table's columns)."""
    return [(m.start(), m.end(), words(m.group(0))) for m in re.finditer(r"\S+(?: \S+)*", line)]


def printed_lines(text, section):
    """A Printed for every number of an output text, tied to its quantity: on a plain line, the line's words; in a
    table (a block of rows under lines without numbers), the row's own words and those of the header part above the
    number's column (and the other columns' header words, which the prose must not name)."""
    found = []
    for block in re.split(r"\n\s*\n", text):
        lines = [re.sub(r"(?<=\d)x\b", "×", line) for line in block.splitlines()]  # a ratio printed "1.36x"
        headers = []
        for line in lines:
            nums = list(NUMBER.finditer(line))
            if not nums:
                if line.strip():
                    headers.append(line)
                continue
            own = words(NUMBER.sub(" ", line))
            units = frozenset(_line_units(line) | {u for h in headers for u in _line_units(h)})
            table = len(nums) >= 2 and headers and re.search(r"\S\s{2,}\S", headers[-1])
            for m in nums:
                v, sig = value(m)
                context, other, column = set(own), set(), None
                if table:
                    column = set()
                    row = _segments(line)
                    label = not NUMBER.fullmatch(row[0][2] and line[row[0][0] : row[0][1]] or "0")
                    k = nums.index(m)
                    for h in headers:
                        segs = _segments(h)
                        if label and len(segs) != len(row) and segs[0][0] == 0:
                            segs = segs[1:]
                        if not segs:
                            continue
                        if len(segs) == len(row):
                            best = segs[next(j for j, r in enumerate(row) if r[0] <= m.start() < r[1] + 1)]
                        elif len(nums) % len(segs) == 0:
                            best = segs[k // (len(nums) // len(segs))]
                        else:
                            mid = (m.start() + m.end()) / 2
                            hit = [sg for sg in segs if sg[0] <= m.end() and m.start() <= sg[1]]
                            best = hit[0] if hit else min(segs, key=lambda sg: abs((sg[0] + sg[1]) / 2 - mid))
                        context |= best[2]
                        column |= best[2]
                        other |= set().union(*(sg[2] for sg in segs if sg is not best))
                elif len(own) < 2 and headers:
                    context |= words(headers[-1])
                found.append(
                    Printed(
                        abs(v),
                        sig,
                        bool(PRINTED_RATIO.match(line, m.end())),
                        _printed_unit(line, m.end()),
                        units,
                        frozenset(context),
                        section,
                        line.strip(),
                        frozenset(other - context),
                        frozenset(column) if column is not None else None,
                        id(headers) if table else None,
                        frozenset(own),
                        frozenset(
                            words(
                                " ".join(line[: m.start()].split()[-3:]) + " " + " ".join(line[m.end() :].split()[:3])
                            )
                        ),
                    )
                )
    return found


PRINTED_RATIO = re.compile(r"\s?(?:×|x\b|times\b)(?!\s*\d)")


def backing(nb):
    """Every Printed of a notebook: printed by a code cell, or set by one."""
    nb = load(nb)
    sec, _, _ = sections(nb)
    pool = []
    for i, cell in enumerate(nb["cells"]):
        if cell["cell_type"] != "code":
            continue
        pool += printed_lines(outputs(cell), sec[i][-1][1])
        pool += [
            Printed(v, None, False, None, frozenset(), names, sec[i][-1][1])
            for v, names in set_in_code(source(cell), named=True)
        ]
    return pool


def matches(x, sig, v, printed_sig):
    """``x`` written with ``sig`` significant digits is ``v`` (printed with ``printed_sig``) rounded by at most one
    digit, or ``v`` itself."""
    if v == 0 or not math.isfinite(v):
        return False
    if math.isclose(v, x, rel_tol=1e-9):
        return True
    if printed_sig is None:
        return float(f"{v:.{sig}g}") == x
    return float(f"{v:.{sig}g}") == x and printed_sig <= sig + 1


# ----------------------------------------------------------------------------------------------------------------
# the prose

_EQ = r"[1-9]\d?\.[1-9]\d?"
_REF = (
    r"\d+(?:\.\d+)*(?:\s*[–-]\s*\d+(?:\.\d+)*)*"
    r"(?:\s*(?:,\s*and|,\s*also|\(also|,|and|&)\s*\d+(?:\.\d+)*(?:\s*[–-]\s*\d+(?:\.\d+)*)*)*"
)
SEED_MARK = re.compile(
    rf"`make bench`|\b(?:eqs?\.?|Tables?|Figs?\.?|Figures?)\s*{_REF}|§\s*{_REF}"
    rf"|\(\s*{_EQ}(?:\s*(?:[–-]|,|and)\s*{_EQ})*(?=\s*[),;])",
    re.IGNORECASE,
)
CITED = re.compile(
    rf"(?:\b(?P<kind>[Ee]qs?\.?|Tables?|Figs?\.?|Figures?)|(?P<sec>§))\s*(?P<nums>{_REF})"
    rf"|\((?P<bare>\s*{_EQ}(?:\s*(?:[–-]|,|and)\s*{_EQ})*)(?=\s*[),;])"
)
NOT_A_CLAIM = [
    SEED_MARK,
    re.compile(
        rf"\b(?:Labs?|[Ee]xercises?|[Qq]uestions?|Q|Part|[Ss]teps?|[Ss]eeds?|cells?|rows?|columns?|chapters?|ch\.)"
        rf"\s*{_REF}"
    ),
    re.compile(r"\$\$.*?\$\$", re.S),
    re.compile(r"\$[^$\n]+\$"),
    re.compile(r"`[^`\n]+`"),
    re.compile(r"\[[^\]\n]*\]\([^)\n]*\)"),  # a link's target
    re.compile(r"\b(?:refs?\.?|Std|doi:|Data)\s*[\d.()/:]+(?:\s*[–-]\s*\d+)?(?:,\s*\d+)*"),  # a bibliography entry
    re.compile(r"^\W*\(?[a-z]\)\s*\d+(?:\.\d+)?\s*—"),  # a rubric line: "(a) 0.75 — ..."
    re.compile(r"\b\d+(?:\.\d+)?\s*(?:points?|pts?)\b(?!\s+(?:per|of|a|the|in)\b)"),  # the marks of a question
    re.compile(r"\b\d{4}\b(?=[);,]| ?\))"),  # a year in a reference: (Laidig et al., 2021)
    re.compile(r"±\s?90\s?°"),  # the pitch of gimbal lock: geometry, not a result
    # names: ADXL345, 9DOF, 3D, 2n
    re.compile(r"\bWGS-84\b|\b[A-Z]+\d+[A-Z\d]*\b|\b\d+(?![eE][-+−]?\d)[A-Za-z]+\d*\b"),
]
SENTENCE = re.compile(r"(?<=[.!?;])\s+|\n\s*\n|\n(?=\s*(?:[*\-]|\d+[.)]|\([a-z]\))\s)")
ABBREVIATION = re.compile(r"(?:\b(?:Figs?|[Ee]qs?|e\.g|i\.e|ch|cf|al|vs|refs?|No|approx)\.|\d\.)$")
# a small integer is a claim where it counts something
COUNTED = re.compile(
    r"\s+"
    r"(?:(?!(?:the|a|an|of|and|or|to|in|on|at|by|for|with|per)\b)[A-Za-z]{3,}[\s-]){0,2}?"
    r"(?:trials?|recordings?|samples?|runs?|turns?|periods?|fixes|windows?|"
    r"states?|triads?|positions?|accelerometers?|gyros?|steps|seeds?|filters?|sigma points|cases|"
    r"orders?|knobs?|sweeps?|passes|outages?|users?|students?|axes|rotations?|digits?|bins?)\b",
    re.I,
)


def sentences(text):
    """The sentences of a markdown text (a paragraph or a list item ends one); 'Fig.', 'eq.', 'e.g.' do not end a
    sentence."""
    out = []
    for piece in SENTENCE.split(text):
        if out and ABBREVIATION.search(out[-1].rstrip()):
            out[-1] += " " + piece
        else:
            out.append(piece)
    return out


def prose(cell):
    """The text of a markdown cell that can claim: no solution markers, no rubric, no display math."""
    text = re.sub(r"### (BEGIN|END) SOLUTION", " ", source(cell))
    text = re.split(r"\*?Rubric\b", text)[0]
    text = re.sub(r"^#+ .*$", " ", text, flags=re.M)  # a heading names, it does not claim
    return re.sub(r"\$\$.*?\$\$", " ", text, flags=re.S)


@dataclass
class Claim:
    cell: int
    shown: str
    x: float
    sig: int
    ratio: bool
    unit: str | None
    window: frozenset
    sentence: str
    cited: list = field(default_factory=list)  # (seed, place) the sentence quotes from
    clause: int = 0
    at: int = 0
    lead: str = ""
    after: frozenset = frozenset()
    clause_words: frozenset = frozenset()
    offset: int = 0
    bench: bool = False  # its paragraph quotes the benchmark
    counted: frozenset | None = None  # a small integer that counts: the noun ("trial")


def _seed_of(text_before, default):
    found = re.findall(r"\bseed (00\d)\b|\((00\d)[ ,]|\b(00\d)(?:'s)? (?:eq|§|Table|Fig)", text_before)
    return next(g for g in found[-1] if g) if found else default


def default_seed(nb):
    m = re.search(r"\*\*Follows\*\*[^\n]*?\bseed (00\d)", source(load(nb)["cells"][0]))
    return m.group(1) if m else None


def places(sentence, seed):
    """The seed places a sentence cites, as (seed, 'eq 3.35' / 'Table 7.1' / 'Fig 7.4' / '§7.4.3'); a range cites
    its ends and what lies between (compared as numbers)."""
    out = []
    for m in CITED.finditer(sentence):
        s = _seed_of(sentence[: m.start()], seed)
        kind = "eq" if m.group("bare") else (m.group("kind") or m.group("sec")).lower().rstrip(".")
        nums = m.group("bare") or m.group("nums")
        kind = {"eqs": "eq", "tables": "table", "figs": "fig", "figure": "fig", "figures": "fig"}.get(kind, kind)
        for part in re.split(r"\s*(?:,\s*and|,\s*also|\(also|,|and|&)\s*", nums):
            ends = re.split(r"\s*[–-]\s*", part.strip())
            if ends and ends[0]:
                out.append((s, kind, ends[0], ends[-1]))
    return out


def _key(n):
    return tuple(int(p) for p in n.split("."))


def claims(nb):
    """Every number of the prose that claims something (see tests/test_claims.py), with the words around it."""
    nb = load(nb)
    seed = default_seed(nb)
    found = []
    for i, cell in enumerate(nb["cells"]):
        if cell["cell_type"] != "markdown" or is_header(cell):
            continue
        text = prose(cell)
        pos = 0
        for para in re.split(r"\n\s*\n", text):
            pos = text.find(para, pos)
            for sentence in sentences(para):
                if sentence.rstrip().endswith("?"):
                    continue
                prefix = para[: para.find(sentence)] if sentence in para else ""
                at = source(cell).find(sentence.strip()[:40])
                for c in _claims_of(i, sentence, _seed_of(prefix, seed)):
                    c.offset = max(at, 0)
                    c.bench = bool(BENCH.search(para))
                    found.append(c)
    return found


def _claims_of(i, sentence, seed):
    bare = sentence
    for pattern in NOT_A_CLAIM:
        bare = pattern.sub(lambda m: " " * len(m.group(0)), bare)
    bare = RANGE_DASH.sub(lambda m: " " * (len(m.group(0)) - 1) + "–", bare)
    ms = list(NUMBER.finditer(bare))
    cited = places(sentence, seed)
    out = []
    clause_ends = [m.start() for m in re.finditer(r";", sentence)] + [len(sentence)]
    for k, m in enumerate(ms):
        x, sig = value(m)
        counted = None
        if float(x).is_integer() and x <= 10 and not m.group("frac") and not m.group("exp"):
            cm = COUNTED.match(bare, m.end())
            if not cm:
                continue
            counted = frozenset(words(cm.group(0).split()[-1]))
        clause = max([0] + [e + 1 for e in clause_ends if e < m.start()])
        start = max([clause] + [n.end() for n in ms if n.end() <= m.start()])
        window = words(sentence[start : m.start()]) - _unit_words
        j = k
        while not window and j > 0 and ms[j - 1].end() > clause:  # a list: (3.85°, 4.36°) shares its words
            j -= 1
            lead = max([clause] + [n.end() for n in ms if n.end() <= ms[j].start()])
            window = words(sentence[lead : ms[j].start()]) - _unit_words
        nxt = min([e for e in clause_ends if e > m.end()] + [n.start() for n in ms if n.start() > m.end()])
        after = words(sentence[m.end() : nxt]) - _unit_words
        range_end = re.match(r"\s*–\s*\d+(?:\.\d+)?", bare[m.end() :])
        end = m.end() + (range_end.end() if range_end else 0)
        ratio = bool(RATIO.match(bare, m.end())) or bool(RATIO.match(bare, end))
        unit = _unit(bare, m.end()) or (_unit(bare, end) if range_end else None)
        out.append(
            Claim(
                i,
                m.group(0).strip(),
                x,
                sig,
                ratio,
                unit,
                frozenset(window),
                " ".join(sentence.split()),
                cited,
                clause,
                m.start(),
                sentence[max(start, 0) : m.start()],
                frozenset(after),
                frozenset(words(sentence[clause : min(e for e in clause_ends if e >= m.end())]) - _unit_words),
                counted=counted,
            )
        )
    return out


_unit_words = words(" ".join(_UNITS) + " deg rad")


# ----------------------------------------------------------------------------------------------------------------
# seed numbers


def seed_table():
    """{(seed, kind, number): [values]} from tests/seed_numbers.csv."""
    rows = {}
    with open(SEED_TABLE, encoding="utf-8") as f:
        for row in csv.DictReader(line for line in f if not line.startswith("#")):
            kind, num = row["place"].split(" ", 1) if " " in row["place"] else ("§", row["place"].lstrip("§"))
            rows.setdefault((row["seed"], kind.lower(), num.lstrip("§")), []).append(float(row["value"]))
    return rows


def seed_values(cited, table):
    """The values the table lists for the places a sentence cites (a range covers what lies between its ends)."""
    vals = []
    for seed, kind, lo, hi in cited:
        for (s, k, n), v in table.items():
            if s != seed or k != kind:
                continue
            try:
                inside = _key(lo) <= _key(n) <= _key(hi) or n == lo or (kind == "§" and n.startswith(lo + "."))
            except ValueError:
                inside = n == lo
            if inside:
                vals += v
    return vals


BENCH_TABLE = ROOT / "lib" / "fusionlab" / "data" / "capstone_bar.csv"


def bench_numbers():
    """What `make bench` prints, as the course keeps it: the README's table and the per-trial scores of every filter
    on the shipped trials (lib/fusionlab/data/capstone_bar.csv, whole trials and windows)."""
    vals = [value(m)[0] for m in NUMBER.finditer(read_text(ROOT / "README.md"))]
    with open(BENCH_TABLE, encoding="utf-8") as f:
        for row in csv.DictReader(f):
            vals += [float(row[k]) for k in ("total_rmse_deg", "heading_rmse_deg", "inclination_rmse_deg")]
    return vals


# ----------------------------------------------------------------------------------------------------------------
# the verdict

SUMMARY_TITLE = re.compile(r"^(?:Summary|What|Questions)\b", re.I)


def candidates(claim, pool, allowed):
    """The printed or set numbers that could back a claim: equal to the digits it gives, in a section it may use,
    with its unit and (a ratio) printed as a ratio."""
    near = [p for p in pool if (p.section in allowed or p.sig is None) and matches(claim.x, claim.sig, p.value, p.sig)]
    if claim.ratio:
        near = [p for p in near if p.sig is None or p.ratio]
    if claim.unit:
        near = [
            p
            for p in near
            if p.sig is None or p.unit == claim.unit or (p.unit is None and (not p.units or claim.unit in p.units))
        ]
    return near


def same_quantity(claim, p):
    """The words around the claim name what the printed number is (its line, or its row and column), and no other
    column of its table; a line or a prose clause with no words cannot tell, and passes."""
    if p.sig is None:  # set in code: a count only under its own name (runs=10)
        return claim.counted is None or bool(claim.counted & p.context)
    if claim.counted is not None:
        return bool(claim.counted & p.beside)
    if p.table is None or not p.row:
        return True
    return bool(claim.clause_words & p.context)


def restated(claim, p):
    """A number printed in another section backs a restatement only on a line that names what the clause names."""
    return p.sig is not None and bool(claim.clause_words & p.context)


def why_unbacked(claim, near, seeds, bench):
    """None if the claim is backed; else a short reason."""
    if claim.x == 0 or any(same_quantity(claim, p) for p in near):
        return None
    if any(math.isclose(claim.x, v, rel_tol=1e-9) or float(f"{v:.{claim.sig}g}") == claim.x for v in seeds):
        return None
    if claim.bench and any(
        math.isclose(claim.x, v, rel_tol=1e-9) or float(f"{v:.{claim.sig}g}") == claim.x for v in bench
    ):
        return None
    if near:
        return "printed in its section only for another quantity: " + " | ".join(sorted({p.text[:70] for p in near}))
    if claim.cited:
        return "neither printed in its section nor listed in tests/seed_numbers.csv for " + ", ".join(
            f"{s} {k} {lo}" + (f"–{hi}" if hi != lo else "") for s, k, lo, hi in claim.cited
        )
    return "not printed in its section (with its unit) nor set there"


BENCH = re.compile(r"`make bench`|`python -m fusionlab\.bench`")
PAIRED = re.compile(r"\b(?:against|versus|vs\.?|than|compared with)\b[^\d]*$", re.I)


def unpaired(claim, prev, near, near_prev, clause_claims):
    """'10.20° against VQF's 3.14°': two numbers of one table that the prose compares come from one column."""
    if prev is None or prev.clause != claim.clause or not PAIRED.search(claim.lead) or prev.unit != claim.unit:
        return False
    if len([c for c in clause_claims if c.unit == claim.unit]) != 2:
        return False
    tables = [p for p in near if p.table is not None and same_quantity(claim, p)]
    others = [p for p in near_prev if p.table is not None and same_quantity(prev, p)]
    printed = [p for p in near if p.sig is not None and same_quantity(claim, p)]
    if not tables or not others or len(tables) < len(printed):
        return False
    return not any(a.table == b.table and a.column == b.column for a in tables for b in others)


COMPARES = re.compile(
    r"\b(?:larger|smaller|bigger|better|worse|higher|lower|faster|slower|more accurate|less accurate)"
    r"\s+than\b|\brecovers\b|\bstays? near (?:0|zero)\b|\bnear zero\b|\bbeats?\b",
    re.IGNORECASE,
)


def unbacked(nb):
    """(cell, number as written, reason, sentence) for every claim nothing backs; and, with the number "—", every
    sentence that compares results ("larger than", "recovers", "beats") without one backed number."""
    nb = load(nb)
    sec, names, titles = sections(nb)
    pool = backing(nb)
    table = seed_table()
    bench = bench_numbers() if any("bench`" in source(c) for c in nb["cells"]) else []
    everything = set(titles)
    bad, with_number = [], set()
    prev = near_prev = None
    found = claims(nb)
    for c in found:
        own = section_at(sec[c.cell], c.offset)
        allowed = (
            everything if SUMMARY_TITLE.match(titles.get(own, "")) else {own} | referred_sections(c.sentence, names)
        )
        near = candidates(c, pool, allowed)
        if not any(same_quantity(c, p) for p in near):
            near += [p for p in candidates(c, pool, everything) if restated(c, p)]
        reason = why_unbacked(c, near, seed_values(c.cited, table), bench)
        same_clause = [d for d in found if d.cell == c.cell and d.sentence == c.sentence and d.clause == c.clause]
        if (
            not reason
            and prev is not None
            and prev.sentence == c.sentence
            and unpaired(c, prev, near, near_prev, same_clause)
        ):
            reason = "compared with a number of another column of its table"
        if reason:
            bad.append((c.cell, c.shown, reason, c.sentence))
        else:
            with_number.add((c.cell, c.sentence))
        prev, near_prev = c, near
    for i, cell in enumerate(nb["cells"]):
        if cell["cell_type"] != "markdown" or is_header(cell):
            continue
        for sentence in sentences(prose(cell)):
            s = " ".join(sentence.split())
            if not COMPARES.search(s) or s.endswith("?") or SEED_MARK.search(s):
                continue
            than = re.search(r"\bthan\b([^.;:—]*)", s)
            if (i, s) not in with_number or (than and not re.search(r"\d", than.group(1))):
                bad.append((i, "—", "a comparison without its numbers", s))
    return bad
