"""Any run answers its own question: a user's own glTF and OBJ scenes (made here), every
structure, measured by the real harness and analysed with `all`. REPORT.md and the page
open with a table ranking every structure on those scenes; nothing of the report's study
(its tables, claims, the "no row" cells) appears, and the page is checked in Chromium."""

from __future__ import annotations

import json
import math
import os
import struct
import subprocess
from pathlib import Path

import pytest

from accelbench_analysis.cli import main
from accelbench_analysis.inputs.load import load_results
from accelbench_analysis.mapping.structures import structure_table

REPO = Path(__file__).resolve().parents[2]
ACCELBENCH = REPO / "build" / "accelbench"
pytestmark = pytest.mark.skipif(not ACCELBENCH.is_file(), reason=f"{ACCELBENCH} not built")


def terrain_glb(path: Path, n: int = 12) -> None:
    """An n x n height field (2 n^2 triangles) under a node turned and moved, and a camera
    node looking at it: one .glb."""
    pos, idx = [], []
    for j in range(n + 1):
        for i in range(n + 1):
            pos += [i / n - 0.5, 0.1 * math.sin(6 * i / n) * math.cos(5 * j / n), j / n - 0.5]
    for j in range(n):
        for i in range(n):
            a, b, c, d = (
                j * (n + 1) + i,
                j * (n + 1) + i + 1,
                (j + 1) * (n + 1) + i,
                (j + 1) * (n + 1) + i + 1,
            )
            idx += [a, c, b, b, c, d]
    positions = struct.pack(f"<{len(pos)}f", *pos)
    indices = struct.pack(f"<{len(idx)}I", *idx)
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [
            {
                "mesh": 0,
                "rotation": [0, 0.38268343, 0, 0.92387953],
                "scale": [4, 4, 4],
                "translation": [1, 0, 0],
            },
            {"camera": 0, "translation": [1, 1.5, 3], "rotation": [-0.2588190, 0, 0, 0.9659258]},
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.9, "znear": 0.01}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "accessors": [
            {
                "bufferView": 0,
                "componentType": 5126,
                "count": len(pos) // 3,
                "type": "VEC3",
                "min": [-0.5, -0.1, -0.5],
                "max": [0.5, 0.1, 0.5],
            },
            {"bufferView": 1, "componentType": 5125, "count": len(idx), "type": "SCALAR"},
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": len(positions)},
            {"buffer": 0, "byteOffset": len(positions), "byteLength": len(indices)},
        ],
        "buffers": [{"byteLength": len(positions) + len(indices)}],
    }
    js = json.dumps(doc).encode()
    js += b" " * (-len(js) % 4)
    binary = positions + indices
    binary += b"\0" * (-len(binary) % 4)
    total = 12 + 8 + len(js) + 8 + len(binary)
    data = struct.pack("<4sII", b"glTF", 2, total) + struct.pack("<I4s", len(js), b"JSON") + js
    path.write_bytes(data + struct.pack("<I4s", len(binary), b"BIN\0") + binary)


def rocks_obj(path: Path, k: int = 10) -> None:
    """k x k small tetrahedra on a plane: 4 k^2 triangles."""
    lines, v = [], 0
    for j in range(k):
        for i in range(k):
            x, z = i - k / 2, j - k / 2
            lines += [
                f"v {x} 0 {z}",
                f"v {x + 0.8} 0 {z}",
                f"v {x} 0 {z + 0.8}",
                f"v {x + 0.3} 0.7 {z + 0.3}",
            ]
            lines += [f"f {v + 1} {v + 2} {v + 3}", f"f {v + 1} {v + 2} {v + 4}"]
            lines += [f"f {v + 2} {v + 3} {v + 4}", f"f {v + 3} {v + 1} {v + 4}"]
            v += 4
    path.write_text("\n".join(lines) + "\n")


@pytest.fixture(scope="module")
def own_run(tmp_path_factory):
    d = tmp_path_factory.mktemp("own")
    terrain_glb(d / "terrain.glb")
    rocks_obj(d / "rocks.obj")
    (d / "mine.yaml").write_text(
        "name: mine\nrepetitions: 3\nwarmup: 1\ntimeout_s: 120\n"
        "render: {width: 32, height: 24, spp: 1, light: true, shading: false, threads: 1}\n"
        "models:\n  - {path: terrain.glb}\n  - {path: rocks.obj}\n"
        "accelerators:\n  - {name: all}\n"
    )
    out = d / "run"
    subprocess.run(
        [str(ACCELBENCH), "run", str(d / "mine.yaml"), "--out", str(out / "csv" / "mine.csv")], check=True
    )
    assert main(["all", str(out / "csv" / "mine.csv"), "--out", str(out)]) == 0
    return d, out


def test_the_gltf_is_read_with_its_camera_and_says_so(own_run):
    d, out = own_run
    rows = load_results([out / "csv" / "mine.csv"]).rows
    assert set(rows[rows["model"] == "terrain.glb"]["triangles"]) == {2 * 12 * 12}
    inputs = (out / "csv" / "mine.inputs.csv").read_text()
    assert "reader," in inputs and "terrain.glb read by tinygltf " in inputs
    assert "rocks.obj read by" not in inputs


def test_the_report_opens_with_the_ranking_of_every_structure_on_the_users_scenes(own_run):
    _, out = own_run
    rows = load_results([out / "csv" / "mine.csv"]).rows
    text = (out / "REPORT.md").read_text()
    first_table = text[text.index("\n|") : text.index("\n\n", text.index("\n|"))]
    header = first_table.splitlines()[1]
    assert "terrain.glb" in header and "rocks.obj" in header
    labels = set(rows["label"])
    # every structure `{name: all}` runs: the structure table's, but the references and the slow
    in_all = [s for s in structure_table() if s.role != "reference" and not s.slow]
    assert len(labels) >= rows["accel"].nunique() == len(in_all) >= 5
    for label in labels:
        assert f"| {label} |" in first_table, label
    assert "no row" not in text
    assert "A reproduction of the report" not in text and "The report's tables and claims" not in text
    assert "not comparable" not in text
    sections = [line for line in text.splitlines() if line.startswith("## ")]
    assert sections[0] == "## Ranking against Embree" and len(sections) == len(set(sections))
    assert "render threads:" in text.splitlines()[2]


@pytest.mark.skipif(
    os.environ.get("ACCELBENCH_BROWSER") != "required" and not Path("/usr/bin/chromium").exists(),
    reason="no chromium",
)
def test_the_page_shows_the_ranking_first_in_chromium(own_run):
    from chromium import render

    _, out = own_run
    probe = """(() => {
      const t = document.querySelector("main table.data");
      const h2 = [...document.querySelectorAll("main h2")].map((h) => h.textContent);
      return {first: t ? t.querySelector("thead").textContent : "", top: t ? t.getBoundingClientRect().top : -1,
              h2: h2, body: document.body.textContent};
    })()"""
    r = render(out / "index.html", probe, width=1400, height=1400)
    assert r.errors == [] and not [u for u in r.requests if not u.startswith(("file:", "data:"))]
    assert "terrain.glb" in r.facts["first"] and "rocks.obj" in r.facts["first"]
    assert 0 < r.facts["top"] < 1400
    assert r.facts["h2"][0] == "Ranking against Embree"
    assert len(r.facts["h2"]) == len(set(r.facts["h2"]))
    assert "no row" not in r.facts["body"]
