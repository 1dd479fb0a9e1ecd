"""The CSV contract: what loads, what is rejected and with which message, provenance."""

import numpy as np
import pandas as pd
import pytest
from synthetic import row, write_csv

from accelbench_analysis.inputs.load import load_results
from accelbench_analysis.inputs.schema import ContractError, parse_params, read_csv

BUNNY_BVH = {"split": "median", "max_prims": "1", "max_depth": "50", "threads": "1"}


def minimal(tmp_path, name="run.csv", drop=(), **prov):
    rows = [
        row(
            "stanford-bunny",
            "bvh",
            BUNNY_BVH,
            build=0.5,
            render=2.0,
            nodes=138901,
            prim_tests=10,
            node_visits=20,
            tree_depth=17,
            **prov,
        ),
        row("stanford-bunny", "embree", {"threads": "1"}, build=0.1, render=0.5, **prov),
    ]
    return write_csv(tmp_path / name, rows, drop=drop)


def test_loads_the_parameter_and_the_measured_depth_by_name(tmp_path):
    df = read_csv(minimal(tmp_path))
    # The max_depth parameter (the limit) and tree_depth (the depth reached).
    assert df.loc[0, "param.max_depth"] == "50"
    assert df.loc[0, "tree_depth"] == 17.0
    assert df.loc[0, "param_dict"] == {"split": "median", "max_prims": "1", "max_depth": "50", "threads": "1"}
    assert df.loc[0, "build_s_median"] == 0.5


def test_empty_cells_are_missing_not_zero(tmp_path):
    df = read_csv(minimal(tmp_path))
    embree = df[df["accel"] == "embree"].iloc[0]
    assert np.isnan(embree["nodes"]) and np.isnan(embree["prim_tests"])


def test_missing_columns_are_named(tmp_path):
    path = write_csv(
        tmp_path / "bad.csv",
        [row("igea", "bvh", BUNNY_BVH, build=1, render=1)],
        drop=("build_s_median", "cpu"),
    )
    with pytest.raises(ContractError, match=r"missing required columns: build_s_median, cpu"):
        read_csv(path)


def test_non_numeric_value_is_rejected_with_column_and_line(tmp_path):
    path = minimal(tmp_path)
    text = path.read_text().splitlines()
    text[2] = text[2].replace(",0.1,", ",fast,", 1)
    path.write_text("\n".join(text) + "\n")
    with pytest.raises(
        ContractError,
        match=r"run.csv: column 'build_s_median' has non-numeric values on line 3 \(row 2\) \(e.g. 'fast'\)",
    ):
        read_csv(path)


def test_unknown_status_is_rejected(tmp_path):
    path = write_csv(tmp_path / "s.csv", [row("igea", "bvh", BUNNY_BVH, build=1, render=1, status="crashed")])
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
    p = tmp_path / "x.inputs.csv"
    p.write_text("kind,sha256,name\nconfig," + "0" * 64 + ",x\n")
    with pytest.raises(ContractError, match="record of its inputs"):
        read_csv(p)


def test_unknown_ray_set_and_thread_counts_that_are_no_count_rejected(tmp_path):
    rows = [
        row("stanford-bunny", "bvh", BUNNY_BVH, build=1, render=1, extra={"ray_set": "sunbeams"}),
        row("igea", "bvh", BUNNY_BVH, build=1, render=1, render_threads="0.5"),
        row("stanford-dragon", "bvh", BUNNY_BVH, build=1, render=1, render_threads="0"),
    ]
    path = write_csv(tmp_path / "r.csv", rows, extra_columns=("ray_set",))
    with pytest.raises(ContractError) as e:
        read_csv(path)
    msg = str(e.value)
    assert "column 'ray_set' must be one of camera, primary, shadow, ao, diffuse, random" in msg
    assert "['sunbeams'] on line 2 (row 1)" in msg
    assert "column 'render_threads' must be a whole number of at least 1; found ['0', '0.5']" in msg


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


def test_builds_differing_only_in_flags_are_two_groups(tmp_path):
    a = minimal(tmp_path, "a.csv", compile_flags="-O2")
    b = minimal(tmp_path, "b.csv", compile_flags="-O2 -march=native")
    res = load_results([a, b])
    assert res.mixed and [g.label for g in res.groups] == ["A", "B"]
    text = " ".join(res.warnings)
    assert "(differing in compile_flags)" in text and "flags -O2 -march=native" in text


def test_a_file_from_before_the_flags_is_a_build_of_its_own(tmp_path):
    old = minimal(tmp_path, "old.csv", drop=("compile_flags",))
    assert "compile_flags" not in old.read_text().splitlines()[0].split(",")
    assert set(read_csv(old)["compile_flags"]) == {"unknown"}
    res = load_results([old, minimal(tmp_path, "new.csv")])
    assert res.mixed and "(differing in compile_flags)" in " ".join(res.warnings)


def test_dirty_tree_and_debug_build_are_flagged(tmp_path):
    res = load_results([minimal(tmp_path, git_dirty="true", build_type="Debug")])
    text = " ".join(res.warnings)
    assert "dirty work tree" in text and "'Debug'" in text


def test_reps_medians_are_checked(tmp_path):
    path = minimal(tmp_path)
    reps = pd.DataFrame(
        {
            "config": "table4",
            "model": "stanford-bunny",
            "accel": "bvh",
            "params": "split=median;max_prims=1;max_depth=50;threads=1",
            "repetition": [0, 1, 2],
            "build_s": [0.4, 0.5, 0.6],
            "render_s": [1.0, 3.0, 2.5],
        }
    )
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
    with pytest.raises(ContractError, match=r"line 4 \(row 3\): 203 fields but the header has 58"):
        read_csv(path)


# ---- hostile input: every loader refuses it, naming the file, the line/row and the column ----


def _edit_cell(path, line, column, value):
    """Sets one cell (line: 1-based, header = 1) of a CSV written by write_csv."""
    import csv

    with path.open(newline="") as fh:
        rows = list(csv.reader(fh))
    rows[line - 1][rows[0].index(column)] = value
    with path.open("w", newline="") as fh:
        csv.writer(fh).writerows(rows)
    return path


@pytest.mark.parametrize(
    "column", ["build_s_median", "render_s_median", "render_s_mean", "build_s_ci_lo", "render_s_ci_hi"]
)
@pytest.mark.parametrize(
    "value, what",
    [
        ("nan", "values that are not finite"),
        ("NaN", "values that are not finite"),
        ("inf", "values that are not finite"),
        ("-inf", "values that are not finite"),
        ("-0.5", "negative values"),
        ("0", "zero times"),
        ("0.0e0", "zero times"),
    ],
)
def test_broken_times_are_refused_naming_file_line_and_column(tmp_path, column, value, what):
    path = _edit_cell(minimal(tmp_path), 3, column, value)
    with pytest.raises(ContractError) as e:
        load_results([path])
    msg = str(e.value)
    assert msg.startswith(f"{path}: column {column!r} has {what} on line 3 (row 2)"), msg
    assert repr(value) in msg


def test_zero_stddev_is_a_time_but_negative_or_nan_is_not(tmp_path):
    assert read_csv(_edit_cell(minimal(tmp_path), 2, "render_s_stddev", "0")).loc[0, "render_s_stddev"] == 0
    with pytest.raises(ContractError, match=r"'render_s_stddev' has negative values on line 2 \(row 1\)"):
        read_csv(_edit_cell(minimal(tmp_path), 2, "render_s_stddev", "-1e-9"))
    with pytest.raises(ContractError, match=r"'nodes' has values that are not finite on line 2"):
        read_csv(_edit_cell(minimal(tmp_path), 2, "nodes", "inf"))
    with pytest.raises(ContractError, match=r"'rays' has negative values on line 3 \(row 2\)"):
        read_csv(_edit_cell(minimal(tmp_path), 3, "rays", "-307200"))


@pytest.mark.parametrize("cut", [1, 5, 17, 40])
def test_a_last_row_cut_short_is_refused(tmp_path, cut):
    path = minimal(tmp_path)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) - cut])
    with pytest.raises(ContractError) as e:
        read_csv(path)
    msg = str(e.value)
    assert msg.startswith(f"{path}: line 3 "), msg
    assert "cut short" in msg or "no line break at its end" in msg, msg


def test_a_row_with_fields_missing_or_extra_is_refused(tmp_path):
    path = minimal(tmp_path)
    lines = path.read_text().splitlines()
    short = lines[:2] + [lines[2].rsplit(",", 3)[0]]
    path.write_text("\n".join(short) + "\n")
    with pytest.raises(
        ContractError, match=r"line 3 \(row 2\): \d+ fields but the header has \d+ \(the row is cut short\)"
    ):
        read_csv(path)
    path.write_text("\n".join(lines[:2] + [lines[2] + ",extra"]) + "\n")
    with pytest.raises(ContractError, match=r"line 3 \(row 2\): \d+ fields but the header has"):
        read_csv(path)
    path.write_text("\n".join(lines[:2] + [""] + lines[2:]) + "\n")
    with pytest.raises(ContractError, match=r"line 3: an empty line"):
        read_csv(path)


def test_rows_are_counted_by_record_not_by_physical_line(tmp_path):
    """A message with a line break in it (quoted) takes two lines; the row after it is
    still named by the line it starts on."""
    rows = [
        row("igea", "bvh", BUNNY_BVH, status="error", message="line one\nline two"),
        row("igea", "embree", {"threads": "1"}, build=0.1, render=-0.5),
    ]
    path = write_csv(tmp_path / "m.csv", rows)
    with pytest.raises(ContractError, match=r"'render_s_median' has negative values on line 4 \(row 2\)"):
        read_csv(path)


def _with_reps(tmp_path, reps_text):
    path = minimal(tmp_path)
    (tmp_path / "run.reps.csv").write_text(reps_text)
    return path


REPS_HEADER = "config,model,accel,params,repetition,build_s,render_s\n"
BVH_KEY = "table4,stanford-bunny,bvh,split=median;max_prims=1;max_depth=50;threads=1"


@pytest.mark.parametrize(
    "value, what",
    [
        ("nan", "not finite"),
        ("inf", "not finite"),
        ("-2.0", "negative"),
        ("0", "zero times"),
        ("x", "non-numeric"),
    ],
)
def test_reps_with_broken_times_are_refused(tmp_path, value, what):
    path = _with_reps(tmp_path, REPS_HEADER + f"{BVH_KEY},1,0.5,2.0\n{BVH_KEY},2,0.5,{value}\n")
    with pytest.raises(ContractError) as e:
        load_results([path])
    msg = str(e.value)
    assert msg.startswith(f"{tmp_path / 'run.reps.csv'}: column 'render_s' has "), msg
    assert what in msg and "line 3 (row 2)" in msg, msg


def test_reps_cut_short_is_refused(tmp_path):
    path = _with_reps(tmp_path, REPS_HEADER + f"{BVH_KEY},1,0.5,2.0\n{BVH_KEY},2,0.5")
    with pytest.raises(ContractError, match=r"run.reps.csv: line 3 \(row 2\): 6 fields but the header has 7"):
        load_results([path])


def test_check_refuses_with_exit_2_and_names_the_cell(tmp_path, capsys):
    from accelbench_analysis.cli import main

    path = _edit_cell(minimal(tmp_path), 3, "render_s_median", "nan")
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert f"{path}: column 'render_s_median' has values that are not finite on line 3 (row 2)" in err
    data = minimal(tmp_path).read_bytes()
    path.write_bytes(data[:-3])
    assert main(["check", str(path)]) == 2
    assert f"{path}: line 3 (the last row) has no line break at its end" in capsys.readouterr().err


def test_a_file_with_the_old_repeated_names_says_how_to_convert_it(tmp_path):
    # Before the renames the header held max_depth, width and threads twice: the
    # parameter's between params and status, the measured or global one after.
    old = tmp_path / "old.csv"
    old.write_text(
        "config,accel,params,max_depth,status,max_depth,width,height,threads\nc,bvh,,50,ok,17,64,48,1\n"
    )
    with pytest.raises(ContractError) as e:
        read_csv(old)
    for part in (
        "max_depth -> tree_depth",
        "width -> image_width",
        "threads -> render_threads",
        "convert-csv",
    ):
        assert part in str(e.value)


def test_a_file_from_before_fp_mode_and_embree_isa_loads_as_ieee_and_unknown(tmp_path):
    path = write_csv(
        tmp_path / "old.csv",
        [row("stanford-bunny", "embree", {"threads": "1"}, build=0.1, render=0.5)],
        drop=("fp_mode", "embree_isa"),
    )
    df = read_csv(path)
    assert list(df["fp_mode"]) == ["ieee"] and list(df["embree_isa"]) == ["unknown"]
    current = read_csv(minimal(tmp_path))
    assert set(current["fp_mode"]) == {"ftz_daz"} and set(current["embree_isa"]) == {"avx512"}


def test_fp_mode_is_part_of_the_key_and_only_its_two_values_load(tmp_path):
    both = [
        row("stanford-bunny", "embree", {"threads": "1"}, build=0.1, render=0.5, fp_mode=mode)
        for mode in ("ieee", "ftz_daz")
    ]
    assert len(read_csv(write_csv(tmp_path / "both.csv", both))) == 2
    bad = row("stanford-bunny", "embree", {"threads": "1"}, build=0.1, render=0.5, fp_mode="ftz")
    with pytest.raises(
        ContractError, match=r"column 'fp_mode' must be one of ieee, ftz_daz; found \['ftz'\]"
    ):
        read_csv(write_csv(tmp_path / "bad.csv", [bad]))


def test_embrees_kernel_isa_is_provenance(tmp_path):
    a = minimal(tmp_path, "a.csv")
    b = minimal(tmp_path, "b.csv", embree_isa="avx2")
    res = load_results([a, b])
    assert res.mixed and "embree_isa" in " ".join(res.warnings)
