"""The HTML shell every page of the analysis shares (a run's index.html, results/index.html,
results/history/index.html): one self-contained file that opens from file:// with no
network. Its style sheet and script (sortable, filterable tables; Vega-Lite figures) come
from assets/ beside this file; Vega, Vega-Lite and vega-embed are inlined from the
vl-convert-python package (analysis/requirements.txt pins it), never fetched from a CDN;
PNGs are embedded as data: URIs.

A table of class `data` gets sortable headers and, past 10 rows, a filter box; a `<div class="vega">`
followed by a `<script type="application/json" class="vega-spec">` is drawn with
vegaEmbed. When every figure is drawn, the page sets `data-charts="ready"` on <html>
(or "failed" after a console error), which the browser test waits for."""

from __future__ import annotations

import base64
import hashlib
import html
import json
import resource
import subprocess
import sys
from functools import lru_cache
from pathlib import Path

ASSETS = Path(__file__).resolve().parent / "assets"
DOCTYPE = "<!DOCTYPE html>"


# vl-convert's V8 reserves its caged heap (Oilpan's CagedHeap) when it starts: under an
# address-space limit (`ulimit -v`) of 64 GiB or less it dies with "Fatal process out of
# memory"; 128 GiB is enough (measured with vl-convert-python 1.x). So it runs in a child.
V8_ADDRESS_SPACE = "more than 64 GiB of address space (128 GiB is enough)"


@lru_cache(maxsize=1)
def vega_bundle() -> str | None:
    """Vega, Vega-Lite and vega-embed as one classic script that sets window.vegaEmbed.
    vl-convert builds it from the copies inside the package (about 0.9 MB, 2 s the first
    time in a process), in a child process: where V8 cannot start (an address-space limit)
    that is one line on stderr and None, and the pages are written without drawing their
    interactive figures (the PNGs stay), never a job killed by V8's fatal error."""
    code = "import sys, vl_convert; sys.stdout.write(vl_convert.javascript_bundle())"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    if done.returncode == 0 and done.stdout:
        return done.stdout
    limit = resource.getrlimit(resource.RLIMIT_AS)[0]
    shown = "none" if limit == resource.RLIM_INFINITY else f"{limit / 2**30:.1f} GiB"
    print(
        f"pages: interactive figures left undrawn: vl-convert's V8 could not build the Vega bundle "
        f"(exit {done.returncode}; it needs {V8_ADDRESS_SPACE}, the address-space limit is {shown})",
        file=sys.stderr,
    )
    return None


def inline_script(code: str) -> tuple[str, str]:
    """The element and its CSP source ('sha256-...' of its exact text): only the page's own
    scripts run, never one that text from data smuggled in."""
    # "</script" inside a script would close the element early; "<\/" reads the same in JS.
    text = code.replace("</script", "<\\/script")
    digest = base64.b64encode(hashlib.sha256(text.encode("utf-8")).digest()).decode("ascii")
    return "<script>" + text + "</script>", f"'sha256-{digest}'"


def json_script(value, css_class: str) -> str:
    """A JSON document inside the page, read by page.js (JSON.parse of its text)."""
    text = json.dumps(value, separators=(",", ":"), allow_nan=False)
    return f'<script type="application/json" class="{css_class}">' + text.replace("</", "<\\/") + "</script>"


def png_data_uri(path: Path) -> str:
    return "data:image/png;base64," + base64.b64encode(path.read_bytes()).decode("ascii")


def vega_figure(spec: dict, source: str) -> str:
    """An interactive figure: where page.js draws `spec`; `source` names the file it came from."""
    return f'<div class="vega" data-source="{html.escape(source)}"></div>' + json_script(spec, "vega-spec")


def data_table(head: list[str], rows: list[str]) -> str:
    """A sortable, filterable table: header texts, and rows already written as <tr>...</tr>."""
    cells = "".join(f"<th>{html.escape(h)}</th>" for h in head)
    return (
        f'<div class="table-wrap"><table class="data"><thead><tr>{cells}</tr></thead>'
        f"<tbody>{''.join(rows)}</tbody></table></div>"
    )


def write_page(path: Path, text: str) -> Path:
    """Replaces the file at once: a browser never opens half a page."""
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text)
    tmp.replace(path)
    return path


def page(
    title: str, body: str, *, nav: list[tuple[str, str]] = (), charts: bool = False, note: str = ""
) -> str:
    """The whole document. nav: (anchor, label) for the side bar; charts: inline the Vega
    bundle (only pages with interactive figures carry its 0.9 MB)."""
    links = "".join(f'<li><a href="#{html.escape(a)}">{html.escape(label)}</a></li>' for a, label in nav)
    side = f'<nav class="toc"><p class="toc-title">On this page</p><ul>{links}</ul></nav>' if nav else ""
    bundle = vega_bundle() if charts else None
    codes = ([bundle] if bundle else []) + [(ASSETS / "page.js").read_text()]
    own = [inline_script(code) for code in codes]
    scripts = "".join(element for element, _ in own)
    # Scripts by hash only: no 'unsafe-inline', so markup in a label cannot run. Vega
    # compiles its expressions with Function(), hence 'unsafe-eval' (for the hashed ones).
    script_src = " ".join(source for _, source in own) + " 'unsafe-eval'"
    return "\n".join(
        [
            DOCTYPE,
            '<html lang="en" data-charts="pending">',
            "<head>",
            '<meta charset="utf-8">',
            '<meta name="viewport" content="width=device-width, initial-scale=1">',
            # No request may leave the page: the figures and scripts are inline, links stay local.
            '<meta http-equiv="Content-Security-Policy" content="default-src \'none\'; '
            f"img-src data:; style-src 'unsafe-inline'; script-src {script_src}; base-uri 'none'; "
            "form-action 'none'\">",
            f"<title>{html.escape(title)}</title>",
            f"<style>{(ASSETS / 'page.css').read_text()}</style>",
            "</head>",
            "<body>",
            side,
            '<main class="content">',
            f'<p class="page-note">{note}</p>' if note else "",
            body,
            "</main>",
            scripts,
            "</body>",
            "</html>",
            "",
        ]
    )
