"""The peers' section (outputs/report/peers.py) on crafted ray-set rows with known answers:
written, and linked from REPORT.md, when a plugin's structure was measured; absent when none
was."""

from __future__ import annotations

import pytest
from synthetic import EMBREE, SAH, row, write_csv

from accelbench_analysis.cli import main
from accelbench_analysis.inputs.load import load_results
from accelbench_analysis.outputs.report.peers import peer_rows, peer_table

PLUGIN = {
    "plugin_file": "/opt/peers/tinybvh.so",
    "plugin_sha256": "ab" * 32,
    "plugin_version": "tinybvh 1.6.7",
}
EXTRA = ("ray_set", "ray_set_hash", "label", *PLUGIN)
# (accel, params, label, plugin?) -> seconds (build, primary, ao), and the plugin's
# wrong answers on ao rays.
STRUCTURES = {
    ("embree", "embree"): (EMBREE, "Embree", False, (0.2, 0.25, 0.5)),
    ("bvh", "sah"): (SAH, "BVH (binned SAH)", False, (0.1, 0.5, 1.0)),
    ("tinybvh_bvh8", "default"): ({"builder": "default"}, "tinybvh BVH8_CPU", True, (0.3, 0.2, 1.5)),
}
PLUGIN_WRONG = {"false_misses": 3, "false_hits": 0, "prim_mismatches": 1}


def peers_csv(path, with_plugin: bool = True):
    rows = []
    for (accel, _), (params, label, plugin, (build, primary, ao)) in STRUCTURES.items():
        if plugin and not with_plugin:
            continue
        for rs, seconds in (("primary", primary), ("ao", ao)):
            errors = {"false_misses": 0, "false_hits": 0, "prim_mismatches": 0}
            if plugin and rs == "ao":
                errors = dict(PLUGIN_WRONG)
            extra = {"ray_set": rs, "ray_set_hash": f"{rs:0>16}", "label": label}
            extra.update(PLUGIN if plugin else {})
            rows.append(
                row(
                    "stanford-dragon",
                    accel,
                    params,
                    build=build,
                    render=seconds,
                    config="peers",
                    rays=1_000_000,
                    shadow_rays=0,
                    errors=errors,
                    extra=extra,
                )
            )
    return write_csv(path, rows, with_errors=True, extra_columns=EXTRA)


def test_ratios_and_ranks_against_embree(tmp_path):
    table = peer_table(peer_rows(load_results([peers_csv(tmp_path / "peers.csv")])))
    t = table.set_index(["structure", "ray_set"])
    assert t.loc[("tinybvh BVH8_CPU", "primary"), "trace_ratio"] == pytest.approx(0.8)
    assert t.loc[("tinybvh BVH8_CPU", "ao"), "trace_ratio"] == pytest.approx(3.0)
    assert t.loc[("BVH (binned SAH)", "ao"), "trace_ratio"] == pytest.approx(2.0)
    assert t.loc[("tinybvh BVH8_CPU", "primary"), "build_ratio"] == pytest.approx(1.5)
    assert t.loc[("BVH (binned SAH)", "primary"), "build_ratio"] == pytest.approx(0.5)
    # Ranked per set: the plugin first on primary rays, last on ao rays.
    assert [t.loc[(s, "primary"), "rank"] for s in ("tinybvh BVH8_CPU", "Embree", "BVH (binned SAH)")] == [
        1,
        2,
        3,
    ]
    assert [t.loc[(s, "ao"), "rank"] for s in ("Embree", "BVH (binned SAH)", "tinybvh BVH8_CPU")] == [1, 2, 3]
    assert t.loc[("tinybvh BVH8_CPU", "ao"), "from"] == "plugin tinybvh 1.6.7 (tinybvh.so)"
    assert t.loc[("Embree", "ao"), "from"] == "Embree" and t.loc[("BVH (binned SAH)", "ao"), "from"] == "ours"


def test_the_section_appears_with_plugin_rows(tmp_path):
    out = tmp_path / "run"
    assert main(["all", str(peers_csv(tmp_path / "peers.csv")), "--out", str(out)]) == 0
    doc = (out / "tables" / "peers.md").read_text()
    assert (out / "tables" / "peers.csv").is_file() and (out / "figures" / "peers.png").is_file()
    assert (out / "figures" / "peers.vl.json").is_file()
    report = (out / "REPORT.md").read_text()
    assert "](tables/peers.md)" in report
    assert "tables/peers.md" in (out / "index.html").read_text()
    # A run of ray sets only has no row of the report's workload: its header still names
    # the ranked rows' threads and floating-point mode.
    assert "**render threads:** 1" in report.splitlines()[2]
    assert "- **Floating-point mode of the traces:** ftz_daz (" in report
    lines = {
        line.split(" | ")[1]: line for line in doc.splitlines() if line.startswith("| ") and "---" not in line
    }
    # Ordered by the geometric mean of the trace ratios: Embree 1, BVH 2, tinybvh sqrt(2.4).
    assert [line.split(" | ")[0] for line in (lines["Embree"], lines["tinybvh BVH8_CPU"])] == ["| 1", "| 2"]
    plugin = lines["tinybvh BVH8_CPU"]
    assert "0.80 (1)" in plugin and "3.00 (3) [4 wrong]" in plugin
    assert plugin.endswith("| 1.50 | 3 | 0 | 1 |")  # build ratio; false misses, false hits, wrong prims


def test_the_section_does_not_appear_without_plugin_rows(tmp_path):
    out = tmp_path / "run"
    assert main(["all", str(peers_csv(tmp_path / "ours.csv", with_plugin=False)), "--out", str(out)]) == 0
    assert (out / "tables" / "ray_sets.md").is_file()
    assert not (out / "tables" / "peers.md").exists() and not (out / "figures" / "peers.png").exists()
    report = (out / "REPORT.md").read_text()
    assert "tables/peers.md" not in report and "open peers" not in report
