"""A run directory's index.html: REPORT.md as one self-contained page.

The page follows REPORT.md section by section and shows, at the end of each section, what
the section links: a linked Markdown document (tables/table4.md, tables/claims.md, ...)
inline with its tables sortable and filterable; a linked figure with its seaborn PNG
embedded and, where the figure writer left a Vega-Lite spec beside it
(figures/NAME.vl.json, drawn from the same frame as the PNG), the interactive version
above it. Documents and figures of the run that REPORT.md does not link come last, so
nothing the directory holds is missing. Nothing is computed here: every number is the
text the analysis wrote."""

from __future__ import annotations

import html
import json
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

from ..figures.interactive import spec_path
from .markdown_html import first_heading, slug, to_html
from .page import page, png_data_uri, vega_figure, write_page

INDEX = "index.html"
EXTERNAL = re.compile(r"^[a-z][a-z0-9+.-]*:|^#", re.I)


@dataclass
class RunPage:
    run_dir: Path
    shown: set[Path] = field(default_factory=set)  # documents and figures already on the page

    def rel(self, path: Path) -> str:
        return os.path.relpath(path, self.run_dir).replace(os.sep, "/")

    def anchor(self, path: Path) -> str:
        kind = "fig" if path.suffix == ".png" else "doc"
        return f"{kind}-{slug(self.rel(path))}"

    def target(self, href: str, base: Path) -> Path | None:
        """The local document or figure a link points to, when the page can show it."""
        if EXTERNAL.match(href):
            return None
        path = (base / href.split("#")[0]).resolve()
        # Only the run's own files: a label that is a link to ../../elsewhere.md embeds nothing.
        return (
            path
            if path.suffix in (".md", ".png")
            and path.is_relative_to(self.run_dir)
            and path.is_file()
            and path.name != "REPORT.md"
            else None
        )

    def render(self, text: str, base: Path, shift: int, prefix: str, found: list) -> str:
        """Markdown from `base` as HTML; links to documents and figures become anchors on
        this page (appended to `found` with their link text), other local links are made
        relative to the run directory."""

        def link(href: str, label: str) -> str | None:
            t = self.target(href, base)
            if t is not None:
                found.append((t, label))
                return "#" + self.anchor(t)
            if EXTERNAL.match(href):
                return None
            local = (base / href).resolve()
            # Outside the run: "../.." from its folder, which to_html's confinement drops.
            return self.rel(local) if local.is_relative_to(self.run_dir) else "../" + href

        return to_html(text, shift=shift, prefix=prefix, link=link)

    def block(self, path: Path, label: str, is_open: bool = True) -> str:
        self.shown.add(path)
        if path.suffix == ".png":
            return self.figure(path, label)
        return self.document(path, is_open)

    def document(self, path: Path, is_open: bool) -> str:
        text = path.read_text()
        title = first_heading(text) or path.name
        text = re.sub(r"^#\s+.+\n", "", text, count=1, flags=re.M)
        inner: list = []
        body = self.render(text, path.parent, 2, self.anchor(path) + "-", inner)
        return (
            f'<details class="included" id="{self.anchor(path)}" data-source="{html.escape(self.rel(path))}"'
            f"{' open' if is_open else ''}>"
            f'<summary>{html.escape(title)} <span class="source">{html.escape(self.rel(path))}</span></summary>'
            f"{body}</details>"
        )

    def figure(self, png: Path, caption: str) -> str:
        """A figure once: its Vega-Lite specification where it has one (the PNG beside it is
        REPORT.md's), else the PNG."""
        source = self.rel(png)
        img = f'<img src="{png_data_uri(png)}" alt="{html.escape(caption)}" data-source="{html.escape(source)}">'
        spec = spec_path(png)
        if spec.is_file():
            img = (
                '<p class="muted">Hover a point for its structure, parameters and values; '
                "click a legend entry to pick it out.</p>"
                + vega_figure(json.loads(spec.read_text()), self.rel(spec))
            )
        return (
            f'<figure class="figure" id="{self.anchor(png)}" data-source="{html.escape(source)}">'
            f"<figcaption>{html.escape(caption)}</figcaption>{img}</figure>"
        )


def sections(text: str) -> list[tuple[str | None, str]]:
    """REPORT.md cut before each second-level heading: (heading or None, Markdown)."""
    parts = re.split(r"(?m)^(?=## )", text)
    return [
        (first_line[3:].strip() if (first_line := p.split("\n", 1)[0]).startswith("## ") else None, p)
        for p in parts
    ]


def run_page_html(run_dir: Path) -> str:
    run_dir = run_dir.resolve()
    p = RunPage(run_dir)
    report = run_dir / "REPORT.md"
    if not report.is_file():
        raise FileNotFoundError(f"{report}: no REPORT.md to show (run the analysis's `all` first)")
    body, nav, charts = [], [], False
    for heading, text in sections(report.read_text()):
        found: list[tuple[Path, str]] = []
        body.append(p.render(text, run_dir, 0, "", found))
        if heading:
            nav.append((slug(heading), heading))
        for path, label in found:
            if path not in p.shown:
                body.append(p.block(path, label))
    rest = sorted(
        (f for d in ("tables", "figures") for f in (run_dir / d).glob("*.md" if d == "tables" else "*.png")),
        key=lambda f: (f.suffix, f.name),
    )
    rest = [f for f in rest if f.resolve() not in p.shown]
    if rest:
        nav.append(("other-outputs", "Other outputs of this run"))
        body.append('<h2 id="other-outputs">Other outputs of this run</h2>')
        body.append(
            "<p>Written by the analysis in this directory; REPORT.md shows them in its text or not at all.</p>"
        )
        body += [p.block(f.resolve(), f.stem, is_open=False) for f in rest]
    charts = any(spec_path(f).is_file() for f in p.shown if f.suffix == ".png")
    note = (
        f"{html.escape(run_dir.name)}: this directory's REPORT.md with its tables and figures, "
        "self-contained (it opens offline). Tables sort by a click on a column; long ones filter by words."
    )
    return page(f"accelbench results — {run_dir.name}", "\n".join(body), nav=nav, charts=charts, note=note)


def write_run_page(run_dir: Path) -> Path:
    return write_page(run_dir / INDEX, run_page_html(run_dir))
