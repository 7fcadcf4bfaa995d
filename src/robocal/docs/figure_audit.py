"""The audit of documented numbers: every number of README.md and docs/*.md that no registered
figure (:data:`robocal.docs.figure_registry.FIGURES`) checks and that does not look like an input,
a constant or a citation.

A number is *covered* when a registered figure's pattern finds it (the span of its first group).
It is *exempt* (not a result) when it is

* inside a fenced code block, an inline code span, a link target or an HTML comment (commands,
  option values, file contents, addresses);
* an integer without a percent sign (a count, an index, a size, a setting: results are printed with
  decimals; integer results such as counts of identified parameters are registered where found);
* part of a name (``A4``, ``UR10``, ``theta3``, ``r1``, ``SE(3)``, ``3-D``), an ordinal (``2nd``),
  a date (``2026-11-27``) or a clock time;
* a timing (followed by ``s``, ``ms``, ``us``, ``µs``, ``min``, ``h``, ``seconds``, ``minutes``, ``hours``)
  or a speed ratio (``2.8x faster``): timings belong to benchmarks/README.md and are not checked;
* an input or a bound: followed by ``noise``, ``tolerance``, ``limit``, ``box``, ``margin``, ...,
  or after ``<``, ``>``, ``±`` (not a value's ``± U``), ``within``, ``below``, ``up to``, ``noise``;
* in a table column whose header names a time, a speed or a memory size or a cited source
  (README, source, thesis, paper, published, reference) or in such a row, or in a row's first
  cell or the header row (labels: the set-up measured);
* a reference (after ``section``, ``table``, ``figure``, ``eq.``, ``issue``, ``item``, ``chapter``,
  ``step``, ``§``, ``(thesis``), a version (after ``Python``, ``numpy``, ``>=``, ``v``), a default
  (``default 0.5``) or a heading's number;
* on a line marked as citing a published value (``published``, ``cited``, ``datasheet``, ``the
  thesis's``, ``the paper's``, ``manufacturer``);
* matched by an entry of the allow-list ``figure_audit_allow.txt`` (``file<TAB>regex`` per line:
  inputs and published constants that the heuristics above miss, each with a reason).

What remains is listed by ``python -m robocal.docs.figures --audit``; ``tests/test_doc_figure_audit.py``
checks that no page's count grows beyond ``figure_audit_baseline.json`` (lower the baseline when
you register a figure or add an allow-list entry).
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from pathlib import Path

__all__ = ["Number", "audit", "audited_files", "baseline", "uncovered_counts"]

_HERE = Path(__file__).resolve().parent
ALLOW_FILE = _HERE / "figure_audit_allow.txt"
BASELINE_FILE = _HERE / "figure_audit_baseline.json"

_NUMBER = re.compile(r"(?<![\w.])(?:[−-](?=\d))?\d+(?:,\d{3})*(?:\.\d+)?(?:e[−+-]?\d+)?")
_UNIT_SUFFIX = re.compile(r"(?:mm|deg|px|mrad|rad|um|µm|m|kg|kNm|Nm|N|ppm|Hz|kHz|MB|GB|K|C|°C|%)\b")
_TIMING = re.compile(r"\s?(?:s|ms|us|µs|ns|min|h|seconds?|minutes?|hours?)\b(?![-/]?(?:pose|point))")
_SPEED = re.compile(r"\s?[x×]\b")
_BEFORE_REF = re.compile(r"(?<!\w)(?:section|sections|table|tables|figure|figures|fig\.|eq\.|eqs\.|equation|issue|issues|item|"
                         r"items|chapter|step|steps|page|§|thesis|line|lines|column|columns|row|rows|rule|level|"
                         r"generation|generations|source|target|python|numpy|scipy|numba|opencv|deap|dask|version|v|>=|<=|==|"
                         r"default|defaults|seed|seeds|cycle|cycles|iso|din|en|vdi|rfc|pep|class|format)"
                         r"[\s(:]*(?:[0-9.]+(?:[-–,/]|\s(?:and|to|or)\s)\s?)*$", re.I)
_DATE = re.compile(r"\d{4}-\d{2}-\d{2}|\d{1,2}:\d{2}(?::\d{2})?(?:\s?UTC)?")
_CITED = re.compile(r"published|cited|README reference|reference fit|datasheet|manufacturer|thesis's|the paper's|the source's|the README's|"
                    r"the dataset's README", re.I)
_SETTING_AFTER = re.compile(r"\s?(?:mm|°|deg|px|rad|mrad|µm|um|ppm|%)?\s?(?:\w+ ){0,1}(?:noise|tolerance|threshold|limit|box|"
                            r"margin|spacing|pitch|steps?|prior)\b", re.I)
_SETTING_BEFORE = re.compile(r"(?:[<>≤≥]=?|±|\+-|within|below|above|under|over|at most|at least|up to|noise(?: of)?|"
                             r"sigma|σ =|tolerance|threshold|limit|max\(|min\()\s?\(?$", re.I)
_TIMING_HEADER = re.compile(r"time|\[s\]|\[ms\]|\[us\]|\[µs\]|\[min\]|speed|memory|KiB|MiB|per second|/s\b", re.I)
_CITED_HEADER = re.compile(r"README|source|thesis|paper|published|reference|datasheet", re.I)
_INLINE = re.compile(r"``[^`]*``|`(?:[^`\n]|\n(?!\n))*`|\]\([^)]*\)|<!--.*?-->|https?://\S+|<[^>\n]*>")


@dataclass(frozen=True)
class Number:
    """One numeric token of a page: ``file`` (relative), ``line`` (1-based), ``text`` (as printed),
    ``context`` (the line, stripped)."""

    file: str
    line: int
    text: str
    context: str


def audited_files(root: Path) -> list:
    """README.md and docs/*.md, relative to ``root``."""
    return [f for f in ["README.md"] + sorted(f"docs/{p.name}" for p in (root / "docs").glob("*.md"))
            if (root / f).is_file()]


def _allow(root: Path) -> list:
    """The allow-list: (file, compiled regex)."""
    out = []
    for raw in ALLOW_FILE.read_text(encoding="utf-8").splitlines():
        if not raw.strip() or raw.startswith("#"):
            continue
        file, _, rx = raw.partition("\t")
        out.append((file.strip(), re.compile(rx.split("\t")[0])))
    return out


def _covered_spans(root: Path) -> dict:
    """Character spans (start, end) of every registered figure's number, per file."""
    from .figure_registry import FIGURES

    texts, spans = {}, {}
    for fig in FIGURES:
        if not (root / fig.file).is_file():
            continue
        text = texts.setdefault(fig.file, (root / fig.file).read_text(encoding="utf-8"))
        m = re.search(fig.pattern, text)
        if m:
            spans.setdefault(fig.file, []).append(m.span(1))
    return spans


def _masked(text: str) -> str:
    """The page with fenced code blocks, inline code, link targets, comments and headings blanked
    (same length, newlines kept), so that offsets stay those of the file."""
    def blank(m):
        return re.sub(r"[^\n]", " ", m.group(0))

    text = re.sub(r"(?ms)^(```|~~~).*?^\1[^\n]*$", blank, text)
    text = re.sub(r"(?m)^ {4,}\S.*$", lambda m: blank(m) if not m.group(0).lstrip().startswith(("-", "*", "|")) else
                  m.group(0), text)
    text = _INLINE.sub(blank, text)
    text = re.sub(r"(?m)^#{1,6} .*$", blank, text)
    return _DATE.sub(blank, text)


#: an integer followed by this is a solver's iteration count (a result), unless a setting (below)
_ITERATIONS_AFTER = re.compile(r"(?:\s?(?:[-–/]|to|and|or)\s?\d[\d,]*)*\s(?:LM\s|Gauss-Newton\s|GN\s)?iterations?\b")
#: an integer followed by this is a count out of a total (``18 of 20 seeds``): a result
_COUNT_OF_AFTER = re.compile(r"\s(?:of|out of)\s\d[\d,]*\b")
#: ... a cap or a setting of one, not a result
_ITERATIONS_SETTING = re.compile(r"(?:cap|caps|limit|max(?:imum)?|at most|up to|within|budget|of|after|--max-iterations)\s*(?:of\s*)?(?:\d[\d,]*\s*(?:[-–/]|to|and|or)\s*)*$", re.I)


def _exempt(masked: str, start: int, end: int, line: str) -> bool:
    """Whether the number at ``masked[start:end]`` is not a result (module docstring)."""
    after = masked[end:end + 40]
    before = masked[max(0, start - 40):start]
    text = masked[start:end]
    if "." not in text and "e" not in text and not re.match(r"\s?%", after):
        if not ((_ITERATIONS_AFTER.match(after) and not _ITERATIONS_SETTING.search(before))
                or (_COUNT_OF_AFTER.match(after) and not _ITERATIONS_SETTING.search(before))):
            return True  # an integer: a count, an index, a size or a setting (results are printed with decimals)
        # ... except an iteration count of a solve (``1324 iterations``, ``870-1619 LM iterations``) or a
        # count out of a total (``18 of 20 seeds``, ``4 of 24 found``): results
    if after[:1].isalpha() and not _UNIT_SUFFIX.match(after):
        return True  # 3rd, 6D, 2x (a name or an ordinal)
    if before[-1:] in "([" and re.search(r"[A-Z]{2}\($", before):
        return True  # SE(3), SO(3)
    if re.match(r"-D\b|-DOF\b|-dof\b|-axis\b|-joint\b|-bit\b", after):
        return True
    if _TIMING.match(after) or (_SPEED.match(after) and re.search(r"faster|slower|speed|time", line, re.I)):
        return True
    if _BEFORE_REF.search(before):
        return True
    if _SETTING_AFTER.match(after) or (_SETTING_BEFORE.search(before) and not re.search(r"\d\s?±\s?$", before)):
        return True  # an input or a bound (noise 0.02 mm, < 5 mm, within 10 %, ±0.5 mm), not a result
    return bool(_CITED.search(line))


def _timing_column(lines: list, line_no: int, col: int) -> bool:
    """Whether position ``col`` of table row ``lines[line_no]`` is in a column whose header names a
    time, a speed or a memory size (benchmark figures, not checked)."""
    line = lines[line_no].replace("\\|", "  ")  # an escaped pipe (inside code) separates no cells
    if not line.lstrip().startswith("|"):
        return False
    k = line_no
    while k > 0 and lines[k - 1].lstrip().startswith("|"):
        k -= 1
    header = lines[k].replace("\\|", "  ").strip().strip("|").split("|")
    cell = line[:col].count("|") - 1
    if cell == 0 or k == line_no:
        return True  # a row's label or the header (the set-up measured: an input)
    label = line.strip().strip("|").split("|")[0]
    if _CITED_HEADER.search(label):
        return True  # a row of a cited source (the thesis's runs, a README's reference fit)
    return 0 <= cell < len(header) and bool(_TIMING_HEADER.search(header[cell]) or _CITED_HEADER.search(header[cell]))


def audit(root: Path | None = None) -> list:
    """The uncovered result-like numbers of README.md and docs/*.md (:class:`Number`), in page order."""
    from .figure_producers import repository_root

    root = root or repository_root()
    spans = _covered_spans(root)
    allow = _allow(root)
    out = []
    for file in audited_files(root):
        text = (root / file).read_text(encoding="utf-8")
        masked = _masked(text)
        lines = text.split("\n")
        starts = [0]
        for ln in lines:
            starts.append(starts[-1] + len(ln) + 1)
        rules = [rx for f, rx in allow if f in (file, "*")]
        covered = spans.get(file, [])
        line_no = 0
        for m in _NUMBER.finditer(masked):
            s, e = m.span()
            if any(a <= s < b for a, b in covered):
                continue
            while starts[line_no + 1] <= s:
                line_no += 1
            line = lines[line_no]
            if _exempt(masked, s, e, line) or _timing_column(lines, line_no, s - starts[line_no]):
                continue
            col = s - starts[line_no]
            if any(any(a <= col < b for a, b in (x.span() for x in rx.finditer(line))) for rx in rules):
                continue
            out.append(Number(file, line_no + 1, m.group(0), line.strip()))
    return out


def uncovered_counts(numbers: list) -> dict:
    """``{file: count}`` of :func:`audit`'s numbers."""
    counts = {}
    for n in numbers:
        counts[n.file] = counts.get(n.file, 0) + 1
    return counts


def baseline() -> dict:
    """The stored counts per page (``figure_audit_baseline.json``) that must not grow."""
    return json.loads(BASELINE_FILE.read_text(encoding="utf-8"))["uncovered"]


def write_baseline(counts: dict) -> None:
    """Store ``counts`` as the new baseline (``python -m robocal.docs.figures --audit --write-baseline``)."""
    doc = {"about": "uncovered result-like numbers per page (robocal.docs.figure_audit); must not grow",
           "uncovered": dict(sorted(counts.items()))}
    BASELINE_FILE.write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
