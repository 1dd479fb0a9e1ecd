"""The CSV contract: what loads, what is rejected and with which message, provenance."""

import numpy as np
import pandas as pd
import pytest

from accelbench_analysis.schema import ContractError, load_results, parse_params, read_csv
from synthetic import row, write_csv

BUNNY_BVH = {"split": "median", "max_prims": "1", "max_depth": "50", "threads": "1"}


def minimal(tmp_path, name="run.csv", **prov):
    rows = [row("stanford-bunny", "bvh", BUNNY_BVH, build=0.5, render=2.0, nodes=138901,
                prim_tests=10, node_visits=20, tree_depth=17, **prov),
            row("stanford-bunny", "embree", {"threads": "1"}, build=0.1, render=0.5, **prov)]
    return write_csv(tmp_path / name, rows)


def test_loads_and_resolves_duplicate_column_names(tmp_path):
    df = read_csv(minimal(tmp_path))
    # max_depth is both a parameter and a statistic in the harness's header.
    assert df.loc[0, "param.max_depth"] == "50"
    assert df.loc[0, "max_depth"] == 17.0
    assert df.loc[0, "param_dict"] == {"split": "median", "max_prims": "1", "max_depth": "50",
                                       "threads": "1"}
    assert df.loc[0, "build_s_median"] == 0.5


def test_empty_cells_are_missing_not_zero(tmp_path):
    df = read_csv(minimal(tmp_path))
    embree = df[df["accel"] == "embree"].iloc[0]
    assert np.isnan(embree["nodes"]) and np.isnan(embree["prim_tests"])


def test_missing_columns_are_named(tmp_path):
    path = write_csv(tmp_path / "bad.csv", [row("igea", "bvh", BUNNY_BVH, build=1, render=1)],
                     drop=("build_s_median", "cpu"))
    with pytest.raises(ContractError, match=r"missing required columns: build_s_median, cpu"):
        read_csv(path)


def test_non_numeric_value_is_rejected_with_column_and_line(tmp_path):
    path = minimal(tmp_path)
    text = path.read_text().splitlines()
    text[2] = text[2].replace(",0.1,", ",fast,", 1)
    path.write_text("\n".join(text) + "\n")
    with pytest.raises(ContractError, match=r"'build_s_median' has non-numeric values on lines \[3\]"):
        read_csv(path)


def test_unknown_status_is_rejected(tmp_path):
    path = write_csv(tmp_path / "s.csv", [row("igea", "bvh", BUNNY_BVH, build=1, render=1,
                                              status="crashed")])
    with pytest.raises(ContractError, match="status"):
        read_csv(path)


def test_duplicate_key_in_one_file_is_rejected(tmp_path):
    r = row("igea", "bvh", BUNNY_BVH, build=1, render=1)
    with pytest.raises(ContractError, match="must be unique"):
        read_csv(write_csv(tmp_path / "d.csv", [r, r]))


def test_reps_file_is_not_a_summary(tmp_path):
    p = tmp_path / "x.reps.csv"
    p.write_text("config,model,accel,params,repetition,build_s,render_s\n")
    with pytest.raises(ContractError, match="per-repetition"):
        read_csv(p)


def test_malformed_params_rejected():
    with pytest.raises(ContractError, match="malformed"):
        parse_params("split=median;oops")
    assert parse_params("a=1.0;b= true ;c=sah") == {"a": "1", "b": "true", "c": "sah"}


def test_single_provenance_has_no_warning(tmp_path):
    res = load_results([minimal(tmp_path)])
    assert len(res.groups) == 1 and not res.mixed and res.warnings == []


def test_mixed_commits_and_machines_are_flagged(tmp_path):
    a = minimal(tmp_path, "a.csv")
    b = minimal(tmp_path, "b.csv", git_sha="f" * 40, cpu="Other CPU")
    res = load_results([a, b])
    assert res.mixed and [g.label for g in res.groups] == ["A", "B"]
    text = " ".join(res.warnings)
    assert "MIXED PROVENANCE" in text and "git_sha, cpu" in text
    assert set(res.rows["prov_group"]) == {"A", "B"}
    # The same keys occur in both files: flagged too.
    assert any("more than one file" in w for w in res.warnings)


def test_dirty_tree_and_debug_build_are_flagged(tmp_path):
    res = load_results([minimal(tmp_path, git_dirty="true", build_type="Debug")])
    text = " ".join(res.warnings)
    assert "dirty work tree" in text and "'Debug'" in text


def test_reps_medians_are_checked(tmp_path):
    path = minimal(tmp_path)
    reps = pd.DataFrame({"config": "table4", "model": "stanford-bunny", "accel": "bvh",
                         "params": "split=median;max_prims=1;max_depth=50;threads=1",
                         "repetition": [0, 1, 2], "build_s": [0.4, 0.5, 0.6],
                         "render_s": [1.0, 3.0, 2.5]})
    reps.to_csv(tmp_path / "run.reps.csv", index=False)
    res = load_results([path])
    assert res.reps is not None and len(res.reps) == 3
    # build median 0.5 agrees; render median of the reps is 2.5, the summary says 2.0.
    assert len(res.warnings) == 1 and "render_s_median" in res.warnings[0]


def test_error_columns_optional(tmp_path, realistic):
    assert not load_results([minimal(tmp_path)]).has_error_columns()
    assert realistic.has_error_columns()


def test_ragged_csv_is_a_contract_error(tmp_path):
    path = minimal(tmp_path)
    path.write_text(path.read_text() + "a,b,c" + ",x" * 200 + "\n")
    with pytest.raises(ContractError, match="well-formed"):
        read_csv(path)
