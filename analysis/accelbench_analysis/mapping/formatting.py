"""Number formatting and the Markdown / LaTeX writers shared by every table."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import pandas as pd

SIGNIFICANT = 3  # digits shown for measured times and ratios


def is_missing(x) -> bool:
    return x is None or (isinstance(x, float) and math.isnan(x))


def _decimals(x: float, sig: int) -> int:
    if x == 0 or not math.isfinite(x):
        return 0
    return max(0, sig - 1 - math.floor(math.log10(abs(x))))


def fmt_sig(x, sig: int = SIGNIFICANT) -> str:
    """3 significant digits, never in exponent notation, thousands separated."""
    if is_missing(x):
        return "—"
    if not math.isfinite(x):
        return str(x)
    d = _decimals(x, sig)
    # Rounding can carry into a new digit (9.996 -> 10.0): recompute on the rounded value.
    d = _decimals(round(x, d), sig) if round(x, d) != 0 else d
    return f"{x:,.{d}f}"


def fmt_count(x) -> str:
    if is_missing(x):
        return "—"
    return f"{int(round(x)):,}"


def ci_label(coverages) -> str:
    """ "CI" with the coverage the intervals shown really have (the harness's `ci_coverage`
    of their rows, an order-statistics interval's exact coverage): "CI 75%", or
    "CI 75-97%" where the rows differ; "CI" when no row has an interval."""
    numbers = pd.to_numeric(pd.Series(list(coverages), dtype=object), errors="coerce").dropna()
    values = sorted({round(float(c) * 100) for c in numbers})
    if not values:
        return "CI"
    return f"CI {values[0]}%" if len(values) == 1 else f"CI {values[0]}-{values[-1]}%"


def _measuring_kind(repetitions: float, processes: float) -> str:
    reps = f"{repetitions:g} repetition{'' if repetitions == 1 else 's'}"
    if math.isnan(processes):
        return f"{reps}, processes not recorded"
    if processes == 1:
        return f"{reps} in one process"
    return f"{reps} pooled from {processes:g} processes"


def repetitions_text(rows: pd.DataFrame) -> str:
    """How the timed rows were measured, from their `repetitions` and `processes` columns:
    "6 repetitions pooled from 2 processes", "3 repetitions in one process"; where the rows
    differ, each kind with its row count, the most common first. A CSV without `processes`
    (or a row that leaves it empty) says "processes not recorded": unknown, never one."""
    if "repetitions" not in rows or rows.empty:
        return "no timed row"
    reps = pd.to_numeric(rows["repetitions"], errors="coerce")
    procs = pd.to_numeric(rows["processes"], errors="coerce") if "processes" in rows else reps * math.nan
    kinds: dict[str, int] = {}
    for r, p in zip(reps, procs):
        if not math.isnan(r):
            kind = _measuring_kind(r, p)
            kinds[kind] = kinds.get(kind, 0) + 1
    if len(kinds) <= 1:
        return next(iter(kinds), "no timed row")
    ordered = sorted(kinds.items(), key=lambda kv: -kv[1])
    return "; ".join(f"{n} row{'' if n == 1 else 's'} of {kind}" for kind, n in ordered)


def fmt_measure(median, lo=None, hi=None, sig: int = SIGNIFICANT) -> str:
    """A median with its CI in brackets (coverage: ci_label), the bounds at the median's
    precision."""
    if is_missing(median):
        return "—"
    text = fmt_sig(median, sig)
    if is_missing(lo) or is_missing(hi):
        return text
    d = _decimals(median, sig)
    return f"{text} [{lo:,.{d}f}, {hi:,.{d}f}]"


@dataclass
class Cell:
    text: str
    tag: str = ""  # provenance group label, shown only when groups are mixed


@dataclass
class Section:
    """A full-width label row inside a table (e.g. "Build time (s)")."""

    label: str


@dataclass
class TableDoc:
    name: str  # file stem, e.g. "table4"
    title: str
    caption: str
    groups: list[tuple[str, int]]  # top header: (label, span) after the first column
    header: list[str]  # second header row, first column included
    rows: list[list[Cell] | Section]
    notes: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    show_tags: bool = False

    @property
    def lead(self) -> int:
        """Columns before the first group (row labels)."""
        return len(self.header) - sum(span for _, span in self.groups)

    def cell_text(self, c: Cell, latex: bool) -> str:
        text = tex_escape(c.text) if latex else md_escape(c.text)
        if self.show_tags and c.tag:
            text += f"\\textsuperscript{{{c.tag}}}" if latex else f" ⁽{c.tag}⁾"
        return text


def md_escape(text: str) -> str:
    return text.replace("|", "\\|")


def note_item(note: str) -> str:
    """A note as a Markdown list item. A note may begin with the report's own words
    ("#int. tests", "#Primitives"): a leading "#" is escaped, or the item would be a heading."""
    return "- " + ("\\" + note if note.startswith("#") else note)


_TEX = {
    "\\": r"\textbackslash{}",
    "&": r"\&",
    "%": r"\%",
    "$": r"\$",
    "#": r"\#",
    "_": r"\_",
    "{": r"\{",
    "}": r"\}",
    "~": r"\textasciitilde{}",
    "^": r"\^{}",
    "—": "---",
    "≈": r"$\approx$",
    "×": r"$\times$",
    "→": r"$\to$",
    "≥": r"$\geq$",
    "≤": r"$\leq$",
    "⁽": "",
    "⁾": "",
}


def tex_escape(text: str) -> str:
    return "".join(_TEX.get(ch, ch) for ch in text)


def to_markdown(t: TableDoc) -> str:
    out = [f"# {t.title}", ""]
    for w in t.warnings:
        out += [f"> **Warning:** {md_escape(w)}", ""]
    out += [t.caption, ""]
    head, col = list(t.header[: t.lead]), t.lead
    for label, span in t.groups:
        for i in range(span):
            sub = t.header[col + i]
            head.append(f"**{label}** {sub}" if i == 0 else sub)
        col += span
    head += t.header[col:]
    out.append("| " + " | ".join(head) + " |")
    out.append("|" + "|".join([":---"] * t.lead + ["---:"] * (len(head) - t.lead)) + "|")
    for r in t.rows:
        if isinstance(r, Section):
            out.append("| " + " | ".join([f"*{md_escape(r.label)}*"] + [""] * (len(head) - 1)) + " |")
        else:
            out.append("| " + " | ".join(t.cell_text(c, False) for c in r) + " |")
    if t.notes:
        out += ["", "Notes:", ""]
        out += [note_item(n) for n in t.notes]
    return "\n".join(out) + "\n"


def to_latex(t: TableDoc) -> str:
    """A booktabs table; needs \\usepackage{booktabs,graphicx} in the document."""
    ncols = len(t.header)
    # The document numbers its own tables, so name the report's table in words.
    title = t.title.replace("Table", "Report's Table", 1)
    out = [
        "% Generated by accelbench_analysis; needs \\usepackage{booktabs,graphicx}.",
        "\\begin{table}[htbp]",
        "\\centering",
        "\\footnotesize",
        f"\\caption{{{tex_escape(title)}. {tex_escape(t.caption)}}}",
        f"\\label{{tab:{t.name}}}",
    ]
    for w in t.warnings:
        out.append(f"\\par\\textbf{{Warning:}} {tex_escape(w)}\\par\\smallskip")
    out += [
        "\\resizebox{\\textwidth}{!}{%",
        f"\\begin{{tabular}}{{{'l' * t.lead}{'r' * (ncols - t.lead)}}}",
        "\\toprule",
    ]
    if t.groups:
        cells, rules, col = [""] * t.lead, [], t.lead + 1
        for label, span in t.groups:
            cells.append(f"\\multicolumn{{{span}}}{{c}}{{{tex_escape(label)}}}")
            rules.append(f"\\cmidrule(lr){{{col}-{col + span - 1}}}")
            col += span
        out.append(" & ".join(cells) + " \\\\")
        out.append(" ".join(rules))
    out.append(" & ".join(tex_escape(h) for h in t.header) + " \\\\")
    out.append("\\midrule")
    for r in t.rows:
        if isinstance(r, Section):
            out.append(f"\\multicolumn{{{ncols}}}{{l}}{{\\textit{{{tex_escape(r.label)}}}}} \\\\")
        else:
            out.append(" & ".join(t.cell_text(c, True) for c in r) + " \\\\")
    out += ["\\bottomrule", "\\end{tabular}}"]
    if t.notes:
        out.append("\\par\\smallskip\\raggedright")
        out += [f"\\textit{{Note:}} {tex_escape(n)}\\par" for n in t.notes]
    out.append("\\end{table}")
    return "\n".join(out) + "\n"


def md_table(header: list[str], rows: list[list[str]], align: str = "l") -> list[str]:
    """A plain Markdown table (one line per row). `align` has one letter per column, l or r;
    columns beyond it are right-aligned (numbers)."""
    align = align.ljust(len(header), "r")
    out = [
        "| " + " | ".join(md_escape(h) for h in header) + " |",
        "|" + "|".join(":---" if a == "l" else "---:" for a in align) + "|",
    ]
    out += ["| " + " | ".join(md_escape(str(c)) for c in r) + " |" for r in rows]
    return out
