"""The analysis's Markdown (REPORT.md, tables/*.md), rendered as HTML for the pages.

The pages show what the Markdown says, never a number computed again: Python-Markdown
turns the text into an element tree, and a tree processor marks its tables for page.js
(class `data`, numeric cells, one <tbody> per section row such as "*Build time (s)*", so
that sorting stays inside a section), demotes headings under the page's own, gives them
ids, and hands every link to a function that may point it somewhere else. Raw HTML is
escaped and links are confined (`confined`): what the Markdown says comes from data."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from collections.abc import Callable

import markdown
from markdown.treeprocessors import Treeprocessor

NUMERIC_ALIGN = "text-align: right"


def slug(text: str) -> str:
    return re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-") or "section"


def is_section_row(tr: ET.Element) -> bool:
    """A table row that labels the rows after it: text only in its first cell, all emphasis."""
    cells = list(tr)
    if len(cells) < 2 or any(("".join(c.itertext())).strip() for c in cells[1:]):
        return False
    first = cells[0]
    return (first.text or "").strip() == "" and len(first) == 1 and first[0].tag == "em"


def split_sections(table: ET.Element) -> None:
    """One <tbody> per section row (the row first in it, class `section`)."""
    body = table.find("tbody")
    if body is None:
        return
    rows = list(body)
    if not any(is_section_row(r) for r in rows):
        return
    width = max(len(r) for r in rows)
    table.remove(body)
    current = ET.SubElement(table, "tbody")
    for r in rows:
        if is_section_row(r):
            if len(current):
                current = ET.SubElement(table, "tbody")
            r.set("class", "section")
            for empty in list(r)[1:]:  # the label spans the row
                r.remove(empty)
            r[0].set("colspan", str(width))
        current.append(r)


def mark_table(table: ET.Element) -> ET.Element:
    table.set("class", "data")
    for cell in table.iter():
        style = cell.get("style", "")
        if cell.tag in ("td", "th") and style.startswith("text-align"):
            del cell.attrib["style"]  # left is the default; right marks a number column
            if cell.tag == "td" and NUMERIC_ALIGN in style:
                cell.set("class", "num")
    split_sections(table)
    wrap = ET.Element("div", {"class": "table-wrap"})
    wrap.append(table)
    return wrap


SAFE_SCHEME = re.compile(r"^(https?:|mailto:|#)", re.I)
SCHEME = re.compile(r"^[a-z][a-z0-9+.-]*:", re.I)


def confined(href: str) -> bool:
    """Whether a link may stay on a page: a web or mail address, an anchor, or a relative
    path that stays below the page's folder. Not javascript:, data:, file: or any other
    scheme, an absolute path, or a path out through "..": text from data may be a link."""
    if SAFE_SCHEME.match(href):
        return True
    if SCHEME.match(href) or href.startswith(("/", "\\")):
        return False
    depth = 0
    for part in href.split("#")[0].split("?")[0].replace("\\", "/").split("/"):
        depth += -1 if part == ".." else (0 if part in ("", ".") else 1)
        if depth < 0:
            return False
    return True


class PageTree(Treeprocessor):
    """Marks tables, shifts headings by `shift` levels with ids under `prefix`, and
    rewrites each link's href with `link(href, text)` (None: keep it), `text` being the
    first link's text in the link's list item or paragraph (what it is a link to: "[Thread
    scaling](...) ... ([figure](...))" names the figure "Thread scaling")."""

    def __init__(self, md, shift: int, prefix: str, link: Callable[[str, str], str | None]):
        super().__init__(md)
        self.shift, self.prefix, self.link = shift, prefix, link

    def run(self, root: ET.Element) -> None:
        for holder in list(root.iter()):
            for i, child in enumerate(list(holder)):
                if child.tag == "table":
                    holder.remove(child)
                    holder.insert(i, mark_table(child))
        parent = {c: p for p in root.iter() for c in p}
        for el in root.iter():
            if re.fullmatch(r"h[1-6]", el.tag):
                level = min(6, int(el.tag[1]) + self.shift)
                el.tag = f"h{level}"
                el.set("id", f"{self.prefix}{slug(''.join(el.itertext()))}")
            elif el.tag == "a" and el.get("href"):
                new = self.link(el.get("href"), self.subject(el, parent))
                if new is not None:
                    el.set("href", new)
                if not confined(el.get("href")):
                    del el.attrib["href"]  # the text stays, the link goes
            elif el.tag == "img" and not (el.get("src") or "").startswith("data:image/"):
                el.attrib.pop("src", None)  # a page embeds its own images as data: URIs only

    @staticmethod
    def subject(a: ET.Element, parent: dict) -> str:
        block = a
        while block in parent and block.tag not in ("li", "p"):
            block = parent[block]
        first = next(block.iter("a"), a)
        return "".join(first.itertext()).strip()


class Extension(markdown.Extension):
    def __init__(self, shift: int, prefix: str, link: Callable[[str, str], str | None]):
        super().__init__()
        self.args = (shift, prefix, link)

    def extendMarkdown(self, md) -> None:  # noqa: N802 (Python-Markdown's name)
        md.treeprocessors.register(PageTree(md, *self.args), "accelbench_page", 5)


def to_html(
    text: str,
    *,
    shift: int = 0,
    prefix: str = "",
    link: Callable[[str, str], str | None] = lambda href, text: None,
) -> str:
    """Markdown text as an HTML fragment (the tables extension: the analysis writes pipe tables).
    Raw HTML in the text is shown as text, never passed through: the Markdown holds labels
    and names from configs and CSVs, which are no one's markup."""
    md = markdown.Markdown(extensions=["tables", "sane_lists", Extension(shift, prefix, link)])
    md.preprocessors.deregister("html_block")
    md.inlinePatterns.deregister("html")
    return md.convert(text)


def first_heading(text: str) -> str | None:
    m = re.search(r"^#\s+(.+)$", text, re.M)
    return m.group(1).strip() if m else None
