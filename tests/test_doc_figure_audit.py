"""The audit of documented numbers (robocal.docs.figure_audit, issue 25 item 3): the count of
result-like numbers on README.md and docs/*.md that no registered figure checks must not grow, and
the audit's rules find a result while passing over inputs, timings, code and citations."""

from __future__ import annotations

import re

from robocal.docs.figure_audit import ALLOW_FILE, audit, baseline, uncovered_counts


def test_no_page_has_more_unchecked_numbers_than_its_baseline():
    counts, base = uncovered_counts(audit()), baseline()
    grew = {f: (n, base.get(f, 0)) for f, n in counts.items() if n > base.get(f, 0)}
    assert not grew, (f"pages with new numbers that no figure checks (count, baseline): {grew}; register them "
                      "(robocal/docs/figure_registry.py) or, for an input or a published value, add an entry to "
                      "robocal/docs/figure_audit_allow.txt (python -m robocal.docs.figures --audit lists them)")


def test_allow_list_entries_are_valid():
    for raw in ALLOW_FILE.read_text(encoding="utf-8").splitlines():
        if raw.strip() and not raw.startswith("#"):
            file, rx, reason = raw.split("\t")
            re.compile(rx)
            assert file and reason.strip(), raw


def test_the_audit_finds_a_result_and_passes_over_inputs_timings_code_and_citations(tmp_path):
    (tmp_path / "docs").mkdir()
    (tmp_path / "README.md").write_text("Intro.\n", encoding="utf-8")
    (tmp_path / "docs" / "page.md").write_text(
        "# Section 4.3\n"
        "With 0.02 mm tracker noise the held-out error is 0.123 mm.\n"
        "It took 3.2 s on this machine, 2.5x faster than before.\n"
        "Run `robocal calibrate ur10 m.csv --prior-sigma 0.5` first.\n"
        "```sh\nrobocal simulate tracker ur10 --noise 0.7\n```\n"
        "The thesis's published value is 0.48 mm.\n"
        "Errors stay below 0.15 mm (±0.01 rad box), on 2026-11-27 with numpy 2.2, UR10 and A4.\n"
        "| set-up 0.3 px | result | time [s] |\n|---|---|---|\n| 0.3 px | 1.75 | 12.5 |\n",
        encoding="utf-8")
    found = [(n.line, n.text) for n in audit(tmp_path)]
    assert found == [(2, "0.123"), (12, "1.75")], found


def test_an_iteration_count_is_a_result_but_a_cap_is_not(tmp_path):
    (tmp_path / "docs").mkdir()
    (tmp_path / "README.md").write_text("Intro.\n", encoding="utf-8")
    (tmp_path / "docs" / "page.md").write_text(
        "The full model needs 1324 LM iterations; the seeds need 870-1619 iterations.\n"
        "The protocol's cap of 1000 iterations, at most 50 iterations, 6 poses and 12 images.\n",
        encoding="utf-8")
    found = [(n.line, n.text) for n in audit(tmp_path)]
    assert found == [(1, "1324"), (1, "870"), (1, "1619")], found


def test_a_count_out_of_a_total_is_a_result(tmp_path):
    (tmp_path / "docs").mkdir()
    (tmp_path / "README.md").write_text("Intro.\n", encoding="utf-8")
    (tmp_path / "docs" / "page.md").write_text(
        "The default is closer in 18 of 20 cells; the cap of 1000 iterations.\n", encoding="utf-8")
    found = [(n.line, n.text) for n in audit(tmp_path)]
    assert found == [(1, "18")], found
