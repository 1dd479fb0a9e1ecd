"""The structure table is the registry's (`accelbench list --json`), and the analysis reads
it rather than keeping a list of its own: its labels are the ones the harness writes into
every row, its order is the tables' and figures', and `{name: all}` runs exactly its
structures of the comparison with their declared variants."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest
from synthetic import BVH, row, write_csv

from accelbench_analysis.inputs.load import load_results
from accelbench_analysis.inputs.schema import parse_params
from accelbench_analysis.mapping.selection import Picker, label_of, table_structures
from accelbench_analysis.mapping.structures import (
    ROLES,
    StructureTableError,
    accelbench_path,
    parse_table,
    structure_table,
)
from accelbench_analysis.outputs.figures.figures import structure_frame

REPO = Path(__file__).resolve().parents[2]


def test_the_table_is_the_registrys_in_registry_order():
    table = structure_table()
    listed = subprocess.run([str(accelbench_path()), "list", "--structures"], capture_output=True, text=True)
    names = [line.split("\t")[0] for line in listed.stdout.splitlines()]
    assert [r.name for r in table] == names
    assert {r.role for r in table} <= set(ROLES)
    assert [r.name for r in table if r.role == "baseline"] == ["embree"]
    for r in table:
        assert r.family, r.name
        assert len({v.label for v in r.variants}) == len(r.variants), f"{r.name}: two variants share a label"


def test_the_json_declares_each_parameter_as_the_listing_does():
    """`list --json` carries each structure's description and declared parameters (type,
    default, choices or range, help), the same as the text listing prints, and no plugin
    for a built-in structure."""
    binary = str(accelbench_path())
    doc = json.loads(subprocess.run([binary, "list", "--json"], capture_output=True, text=True).stdout)
    text = subprocess.run([binary, "list"], capture_output=True, text=True).stdout
    kd = next(s for s in doc["structures"] if s["name"] == "kdtree")
    assert kd["plugin"] is None and kd["description"] in text
    params = {p["name"]: p for p in kd["params"]}
    assert params["build"]["type"] == "enum" and params["build"]["choices"] == ["nlogn", "pbrt"]
    assert params["empty_bonus"]["default"] == "0.5" and params["empty_bonus"]["max"] == 1
    assert params["max_depth"]["default"] == "auto" and params["max_depth"]["scene_dependent_default"]
    for s in doc["structures"]:
        for p in s["params"]:
            line = next(x for x in text.splitlines() if x.split()[:1] == [p["name"]] and p["help"] in x)
            assert f"default {p['default']}" in " ".join(line.split()), (s["name"], p["name"])


def test_the_json_names_a_plugins_file_hash_and_version():
    binary = accelbench_path()
    plugin = Path(binary).parent / "test_plugins" / "example_bvh.so"
    if not plugin.exists():
        pytest.skip(f"{plugin} is built with the C++ tests")
    out = subprocess.run(
        [str(binary), "list", "--json", "--plugin", str(plugin)], capture_output=True, text=True
    )
    mine = [s for s in json.loads(out.stdout)["structures"] if s["role"] == "plugin"]
    assert mine and all(s["plugin"]["file"] == str(plugin) for s in mine)
    assert all(len(s["plugin"]["sha256"]) == 64 and s["plugin"]["version"] for s in mine)
    assert all(s["params"] for s in mine)


def test_labels_are_the_ones_the_harness_writes_into_rows():
    """Every row of the committed reference run: the analysis's label of its accelerator and
    parameters is the row's `label` column (the registry's, of the same parameters)."""
    results = load_results(sorted((REPO / "results" / "reference" / "csv").glob("table[45].csv")))
    rows = results.rows
    table = {r.name: r for r in structure_table()}
    checked = 0
    for accel, params, label in zip(rows["accel"], rows["param_dict"], rows["label"]):
        if accel in table and any(dict(v.params).items() <= params.items() for v in table[accel].variants):
            assert label_of(accel, params) == label, (accel, params)
            checked += 1
    assert checked > 20


def test_all_runs_the_comparisons_structures_with_their_variants():
    out = subprocess.run(
        [str(accelbench_path()), "run", "--dry-run=json", str(REPO / "configs" / "ray-sets.yaml")],
        capture_output=True,
        text=True,
        check=True,
    )
    combos = json.loads(out.stdout)["combinations"]
    ran = {label_of(c["accel"], parse_params(c["params"])) for c in combos}
    expected = {s.label for s in table_structures()}
    slow_or_reference = {
        v.label for r in structure_table() if r.slow or r.role == "reference" for v in r.variants
    }
    assert ran == expected and not ran & slow_or_reference


def test_a_run_at_a_structures_defaults_is_drawn(tmp_path):
    """`bvh split=median` at its defaults (max_prims=auto, not the report's literal 1) is
    the median BVH in the figures; the report's tables still require the report's setting."""
    defaults = {**BVH, "max_prims": "auto"}
    rows = [row("stanford-bunny", "bvh", defaults, build=0.1, render=1.0, nodes=1001, prim_tests=10)]
    results = load_results([write_csv(tmp_path / "run.csv", rows)])
    assert "BVH (median)" in set(structure_frame(results)["structure"])
    bvh = Picker(results).structure("bvh")
    assert not Picker(results).pick("stanford-bunny", bvh.table_spec).ok


def test_output_that_is_not_the_table_is_refused():
    with pytest.raises(StructureTableError, match="not the structure table"):
        parse_table('{"structures": [{"name": "x", "role": "friend"}]}')
