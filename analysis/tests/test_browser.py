"""The HTML pages in a real browser: Debian's Chromium, headless, opening them from
file:// with no network. Each page loads with no console error and no request leaving
it, shows every table and figure its directory has (PNGs decoded, Vega-Lite figures
drawn), answers a click on a column header and a filter, and paints a screenshot that is
not blank.

`make test` sets ACCELBENCH_BROWSER=required (its deps step installs chromium), so there
a missing browser fails; run by hand without it, the tests skip where chromium is not
installed."""

from __future__ import annotations

import io
import os
import re
import subprocess
from pathlib import Path

import pytest
from chromium import INSTALL_HINT, executable, render
from PIL import Image

from accelbench_analysis.cli import main

if executable() is None:
    if os.environ.get("ACCELBENCH_BROWSER") == "required":
        pytest.fail(f"no chromium on PATH, but `make test` needs it: {INSTALL_HINT}", pytrace=False)
    pytest.skip(
        f"no chromium on PATH: the HTML pages are not tested in a browser ({INSTALL_HINT})",
        allow_module_level=True,
    )

# What the page did, read in the browser once its figures are drawn.
PROBE = """(() => {
  const count = (sel) => document.querySelectorAll(sel).length;
  const docs = {};
  document.querySelectorAll("details.included[data-source]").forEach((d) => {
    docs[d.dataset.source] = d.querySelectorAll("table.data").length;
  });
  const images = {};
  document.querySelectorAll("img[data-source]").forEach((i) => {
    images[i.dataset.source] = i.complete && i.naturalWidth > 0;
  });
  const figures = {};
  document.querySelectorAll("div.vega[data-source]").forEach((v) => {
    figures[v.dataset.source] = v.dataset.drawn === "true" ? v.querySelectorAll("svg .mark-symbol path, svg .mark-rect path, svg .mark-line path").length : -1;
  });
  const long = Array.from(document.querySelectorAll("table.data")).filter((t) =>
    Array.from(t.tBodies).reduce((n, b) => n + Array.from(b.rows).filter((r) => !r.classList.contains("section")).length, 0) > 10);
  return {docs, images, figures, tables: count("table.data"), long: long.length, filters: count(".table-tools input")};
})()"""

# Sorts the first numeric column of the first filterable table with a section-free body descending
# (two clicks) and filters it by a word of its last row; returns what the rows then read.
INTERACT = """(() => {
  const table = Array.from(document.querySelectorAll("table.data")).find((t) =>
    t.filterBy && t.tBodies.length === 1 && t.tBodies[0].rows.length > 3 &&
    Array.from(t.tBodies[0].rows[0].cells).some((c) => c.classList.contains("num")));
  const col = Array.from(table.tBodies[0].rows[0].cells).findIndex((c) => c.classList.contains("num"));
  const th = table.tHead.rows[table.tHead.rows.length - 1].cells[col];
  th.click(); th.click();
  const values = Array.from(table.tBodies[0].rows).map((r) => r.cells[col].textContent.trim());
  const word = table.tBodies[0].rows[0].cells[0].textContent.trim();
  table.filterBy(word);
  const shown = Array.from(table.tBodies[0].rows).filter((r) => !r.hidden).map((r) => r.cells[0].textContent.trim());
  return {sort: th.getAttribute("aria-sort"), values, word, shown};
})()"""


def number(text: str) -> float | None:
    m = re.match(r"\s*-?[\d,]*\.?\d+", text)
    return float(m.group(0).replace(",", "")) if m else None


def not_blank(png: bytes) -> tuple[bool, str]:
    """A painted page: many colours, no colour on nearly all of it."""
    with Image.open(io.BytesIO(png)) as im:
        rgb = im.convert("RGB")
        colours = rgb.getcolors(maxcolors=1 << 20) or []
        most = max(n for n, _ in colours) / (rgb.width * rgb.height)
    return len(colours) > 50 and most < 0.99, f"{len(colours)} colours, the commonest on {most:.0%}"


def assert_clean(r, page: Path) -> None:
    assert r.errors == [], f"{page}: {r.errors}"
    outside = [u for u in r.requests if not u.startswith(("file:", "data:"))]
    assert outside == [], f"{page} asked the network for {outside}"
    ok, how = not_blank(r.screenshot)
    assert ok, f"{page}: the screenshot looks blank ({how})"


def markdown_tables(path: Path) -> int:
    return sum(1 for line in path.read_text().splitlines() if re.match(r"^\|\s*:?-{3,}", line))


def test_run_page_in_chromium(analysed_run):
    page = analysed_run / "index.html"
    r = render(page, PROBE)
    assert_clean(r, page)
    assert r.facts["charts"] == "ready"
    for md in sorted((analysed_run / "tables").glob("*.md")):
        assert r.facts["docs"].get(f"tables/{md.name}") == markdown_tables(md), md.name
    pngs = {
        f"figures/{p.name}"
        for p in (analysed_run / "figures").glob("*.png")
        if not p.with_name(p.name.replace(".png", ".vl.json")).is_file()
    }
    assert set(r.facts["images"]) == pngs and all(r.facts["images"].values()), r.facts["images"]
    specs = {f"figures/{p.name}" for p in (analysed_run / "figures").glob("*.vl.json")}
    assert len(specs) == 6 and set(r.facts["figures"]) == specs  # claims_factors.vl.json among them
    assert all(n > 0 for n in r.facts["figures"].values()), r.facts["figures"]
    # A filter box on every table of more than 10 rows (a shorter one is read whole).
    assert r.facts["filters"] == r.facts["long"] > 5 and r.facts["tables"] > 10


def test_tables_sort_and_filter_in_chromium(analysed_run):
    r = render(analysed_run / "index.html", INTERACT)
    assert r.errors == []
    assert r.facts["sort"] == "descending"
    values = [v for v in (number(t) for t in r.facts["values"]) if v is not None]
    assert len(values) > 3 and values == sorted(values, reverse=True)
    assert r.facts["shown"] and all(r.facts["word"] in s for s in r.facts["shown"])


def test_history_and_runs_pages_in_chromium(analysed_run, tmp_path):
    """Two commits in a git work tree, the synthetic run measured at each."""
    results = analysed_run.parent.parent
    repo = tmp_path / "repo"
    repo.mkdir()
    git = ["git", "-C", str(repo), "-c", "user.name=t", "-c", "user.email=t@example.com"]
    subprocess.run([*git, "init", "-q"], check=True)
    subprocess.run([*git, "commit", "-q", "--allow-empty", "-m", "measured"], check=True)
    assert (
        main(["history", "--results", str(results), "--out", str(tmp_path / "history"), "--repo", str(repo)])
        == 0
    )
    page = tmp_path / "history" / "index.html"
    r = render(page, PROBE)
    assert_clean(r, page)
    assert r.facts["charts"] == "ready" and r.facts["tables"] >= 2
    assert list(r.facts["figures"].values())[0] > 0
    runs = results / "index.html"
    r = render(runs, PROBE)
    assert_clean(r, runs)
    assert r.facts["tables"] == 1


# Where the first screen's parts end: the ranking's table and the claims' count table.
FIRST_SCREEN = """(() => {
  const table = (id) => {
    const h = document.getElementById(id);
    let e = h && h.nextElementSibling;
    while (e && !(e.matches("div.table-wrap") || e.querySelector("table.data"))) e = e.nextElementSibling;
    return e ? e.getBoundingClientRect().bottom + window.scrollY : -1;
  };
  return {ranking: table("ranking-against-embree"), claims: table("the-report-s-claims"),
          sections: Array.from(document.querySelectorAll("main h2")).map((h) => h.textContent)};
})()"""


def test_the_ranking_and_the_claims_counts_are_on_the_first_screen(analysed_run):
    r = render(analysed_run / "index.html", FIRST_SCREEN, width=1400, height=1400)
    assert r.errors == []
    assert 0 < r.facts["ranking"] < r.facts["claims"] <= 1400, r.facts
    assert r.facts["sections"][:2] == ["Ranking against Embree", "The report's claims"]
    assert len(r.facts["sections"]) == len(set(r.facts["sections"]))  # no section twice


# Markup in every label a run carries (model names, config names, messages): none of it may
# run, add an element, load anything, or embed a file outside the run; the page's own
# scripts (by CSP hash) still draw its figures.
MARKUP = (
    '<img src=x onerror="window.pwned=1"><script>window.pwned=2</script>'
    '<b onclick="window.pwned=3">b</b>[secret](../../../secret.md)[deep](../../../../secret.md)'
)
HARMLESS = """(() => ({
  pwned: window.pwned === undefined ? null : window.pwned,
  scripts: document.querySelectorAll("script:not([type])").length,
  handlers: document.querySelectorAll("[onerror],[onclick],[onload]").length,
  bold: document.querySelectorAll("main b").length,
  secret: document.body.innerText.includes("TOPSECRET"),
  outside: Array.from(document.images).filter((i) => i.getAttribute("src") && !i.src.startsWith("data:")).length,
  markup: document.body.innerText.includes("<script>window.pwned="),
  charts: document.documentElement.dataset.charts,
}))()"""


def test_markup_in_every_label_runs_nothing_and_embeds_nothing_outside(tmp_path):
    from synthetic import BVH, realistic_rows, row, write_csv

    (tmp_path / "secret.md").write_text("# TOPSECRET\n\nnot the run's\n")
    run = tmp_path / "results" / "runs" / "20240101T000000Z-0123456"
    (run / "csv").mkdir(parents=True)
    rows = realistic_rows(with_errors=False)
    for r in rows:
        r["config"] += MARKUP
    for accel, params in (("bvh", BVH), ("embree", {"threads": "1"})):
        rows.append(row(MARKUP, accel, params, build=0.1, render=0.2, nodes=9, config="table4" + MARKUP))
    rows.append(row(MARKUP + "2", "bvh", BVH, status="error", message=MARKUP, config="table4" + MARKUP))
    csv = write_csv(run / "csv" / "table4.csv", rows)
    (run / "run.json").write_text(
        '{"job": {"configs": ["x.yaml<script>window.pwned=4</script>"], "tag": ""}}'
    )
    assert main(["all", str(csv), "--out", str(run)]) == 0
    assert MARKUP in (run / "REPORT.md").read_text() + "".join(
        p.read_text() for p in (run / "tables").glob("*.md")
    )
    assert main(["history", "--results", str(tmp_path / "results"), "--out", str(tmp_path / "h")]) == 0
    for page in (run / "index.html", tmp_path / "h" / "index.html", tmp_path / "results" / "index.html"):
        r = render(page, HARMLESS)
        outside = [u for u in r.requests if not u.startswith(("file:", "data:"))]
        assert outside == [] and not any(u.endswith("secret.md") for u in r.requests), (page, r.requests)
        f = r.facts
        assert f["pwned"] is None and f["handlers"] == 0 and f["bold"] == 0, (page, f)
        assert not f["secret"] and f["outside"] == 0 and f["markup"], (page, f)
        assert f["charts"] == "ready", (page, f)  # the hashed scripts ran: Vega drew its figures
